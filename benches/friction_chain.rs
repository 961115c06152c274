//! The cost of joint friction (issue #38's target: at most twice the frictionless run): a chain
//! of 16 pinned rods (1 kg, 1 m) released horizontal, 2 s of RK4 at 1 ms with projection, with
//! and without pin friction (μ = 0.1, r = 0.02 m) in every joint, on each formulation.
//! `cargo bench --bench friction_chain`; the figures are in `docs/friction.md`, "Cost".

use criterion::{BenchmarkId, Criterion};
use dalembert::integrators::integrate;
use dalembert::Scene;
use dalembert_testkit::chain_scene::planar_chain_toml;

/// The chain's scene for `formulation`, with pin friction in every joint or none.
fn chain(formulation: &str, friction: bool) -> Scene {
    let mut text = planar_chain_toml(16, friction.then_some((0.1, 0.02)));
    text += &format!(
        "[simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"rk4\"\nstep = 1e-3\n\
         output_every = 0.01\nstabilization = \"projection\"\n"
    );
    Scene::from_toml(&text, "chain").expect("the chain's scene")
}

fn main() {
    let mut c = Criterion::default().sample_size(10).configure_from_args();
    let mut group = c.benchmark_group("friction-chain-16");
    for formulation in ["augmented", "embedding", "amalgamated"] {
        for friction in [false, true] {
            let sim = chain(formulation, friction).simulation();
            let name = if friction { "friction" } else { "frictionless" };
            group.bench_function(BenchmarkId::new(name, formulation), |b| {
                b.iter(|| {
                    let mut f = sim.formulation().expect("formulation");
                    integrate(
                        f.as_mut(),
                        sim.start,
                        sim.end,
                        &sim.q,
                        &sim.qd,
                        &sim.integrator,
                        &mut |_| {},
                    )
                    .expect("run")
                })
            });
        }
    }
    group.finish();
    c.final_summary();
}
