//! 10 s of simulation per integrator on the four-bar and the slider-crank (augmented formulation,
//! h = 1 ms; Dormand–Prince at rtol 1e-8). `cargo bench --bench simulation`.

use criterion::{BenchmarkId, Criterion};
use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, ConstraintTreatment, IntegratorOptions, Method};
use dalembert_testkit::mechanisms;

fn main() {
    let mut c = Criterion::default().sample_size(10).configure_from_args();
    let mut group = c.benchmark_group("simulate-10s");
    let scenes = [
        ("four-bar", mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false)),
        (
            "slider-crank",
            mechanisms::slider_crank(std::f64::consts::FRAC_PI_3, 0.0),
        ),
    ];
    let proj = ConstraintTreatment::Projection { tolerance: 1e-10 };
    let methods = [
        (
            "symplectic-euler+projection",
            IntegratorOptions::fixed(Method::SymplecticEuler, 1e-3, 0.01).with_treatment(proj),
        ),
        ("rk4", IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.01)),
        (
            "rk4+projection",
            IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.01).with_treatment(proj),
        ),
        (
            "dopri5",
            IntegratorOptions::fixed(
                Method::DormandPrince {
                    rtol: 1e-8,
                    atol: 1e-10,
                },
                1e-3,
                0.01,
            )
            .with_treatment(proj),
        ),
        (
            "generalized-alpha",
            IntegratorOptions::fixed(Method::GeneralizedAlpha { rho_inf: 0.8 }, 1e-3, 0.01),
        ),
    ];
    for (scene, mech) in &scenes {
        for (name, opts) in &methods {
            let mut f = Augmented::with_defaults(mech.model.clone()).expect("augmented");
            group.bench_with_input(BenchmarkId::new(*name, scene), mech, |b, mech| {
                b.iter(|| integrate(&mut f, 0.0, 10.0, &mech.q, &mech.qd, opts, &mut |_| {}).expect("run"))
            });
        }
    }
    group.finish();
    c.final_summary();
}
