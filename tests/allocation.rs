//! The stepping loop allocates nothing after setup: a counting global allocator shows that running
//! twice as many steps costs no more allocations (setup is the same; any per-step allocation would
//! add hundreds). The shorter run, made first, may count one or two more for lazily initialized
//! library state; the test therefore requires `long ≤ short`. Augmented formulation, dense (four-bar) and sparse (chain of 64) back ends.

use dalembert::augmented::{Augmented, AugmentedOptions, Backend};
use dalembert::integrators::{integrate, ConstraintTreatment, IntegratorOptions, Method};
use dalembert_testkit::mechanisms::{self, Mechanism};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations(mech: &Mechanism, backend: Backend, opts: &IntegratorOptions, t_end: f64) -> usize {
    let mut f = Augmented::new(
        mech.model.clone(),
        AugmentedOptions {
            backend,
            ..Default::default()
        },
    )
    .unwrap();
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    integrate(&mut f, 0.0, t_end, &mech.q, &mech.qd, opts, &mut |_| {}).unwrap();
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

#[test]
fn stepping_allocates_nothing_after_setup() {
    let four_bar = mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false);
    let chain = mechanisms::chain(1.0, 1.0, &[-0.3; 64], &[0.0; 64], &[]);
    // Every integrator, including the implicit one, with the augmented formulation.
    let proj = ConstraintTreatment::Projection { tolerance: 1e-10 };
    let baum = ConstraintTreatment::baumgarte_for_step(1e-3);
    let cases = [
        (
            "symplectic Euler + Baumgarte",
            IntegratorOptions::fixed(Method::SymplecticEuler, 1e-3, 0.1).with_treatment(baum),
        ),
        ("RK4", IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.1)),
        (
            "RK4 + projection",
            IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.1).with_treatment(proj),
        ),
        (
            "Dormand-Prince",
            IntegratorOptions::fixed(
                Method::DormandPrince {
                    rtol: 1e-8,
                    atol: 1e-10,
                },
                1e-3,
                0.1,
            ),
        ),
        (
            "generalized-alpha",
            IntegratorOptions::fixed(Method::GeneralizedAlpha { rho_inf: 0.8 }, 1e-3, 0.1),
        ),
    ];
    let mut failures = Vec::new();
    for (mech, backend, what) in [
        (&four_bar, Backend::Dense, "four-bar, dense"),
        (&chain, Backend::Sparse, "chain of 64, sparse"),
    ] {
        for (name, opts) in &cases {
            // The chain's implicit steps are costly (finite-difference Jacobians): shorter runs.
            let scale = if backend == Backend::Sparse { 0.1 } else { 1.0 };
            let short = allocations(mech, backend, opts, 0.5 * scale);
            let long = allocations(mech, backend, opts, scale);
            if long > short {
                failures.push(format!("{what}, {name}: {short} allocations for 0.5 s, {long} for 1 s"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
