//! 10 s of simulation per integrator on the four-bar and the slider-crank (augmented formulation,
//! h = 1 ms; Dormand–Prince at rtol 1e-8). `cargo bench --bench simulation`.

use criterion::{BenchmarkId, Criterion};
use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, IntegratorOptions, Method, Stabilization};
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
    let proj = Stabilization::Projection { tolerance: 1e-10 };
    let methods = [
        (
            "symplectic-euler+projection",
            IntegratorOptions::fixed(Method::symplectic_euler(), 1e-3, 0.01).with_stabilization(proj),
        ),
        ("rk4", IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.01)),
        (
            "rk4+projection",
            IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.01).with_stabilization(proj),
        ),
        (
            "dopri5",
            IntegratorOptions::fixed(Method::dopri5(1e-8, 1e-10), 1e-3, 0.01).with_stabilization(proj),
        ),
        (
            "generalized-alpha",
            IntegratorOptions::fixed(Method::generalized_alpha(0.8), 1e-3, 0.01),
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
