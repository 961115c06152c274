//! One forward-dynamics evaluation (`q̈`, `λ`) per formulation on the reference scenes and on chains
//! of N rods; the anchors' spatial chain (chain3d) in absolute and in joint coordinates (the
//! articulated-body algorithm); then the scaling exponent of the augmented formulation's cost
//! against N (fitted on N = 64 … 4096, printed at the end).
//!
//! `cargo bench --bench evaluation` (add `-- --quick` for a fast pass).

use criterion::{BenchmarkId, Criterion};
use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::system::Formulation;
use dalembert::system::MultibodySystem as _;
use dalembert_testkit::closed_form::DoublePendulum;
use dalembert_testkit::mechanisms::{self, Mechanism};
use std::hint::black_box;
use std::time::Instant;

fn formulation(kind: &str, mech: &Mechanism) -> Box<dyn Formulation> {
    match kind {
        "augmented" => Box::new(Augmented::with_defaults(mech.model.clone()).expect("augmented")),
        "embedding" => Box::new(Embedding::with_defaults(mech.model.clone())),
        _ => Box::new(Amalgamated::with_defaults(mech.model.clone())),
    }
}

fn chain(n: usize) -> Mechanism {
    let angles: Vec<f64> = (0..n).map(|k| -0.3 - 0.01 * k as f64).collect();
    mechanisms::chain(1.0, 1.0, &angles, &vec![0.1; n], &[])
}

fn scenes() -> Vec<(String, Mechanism)> {
    let mut v = vec![
        (
            "pendulum".to_string(),
            mechanisms::chain(1.0, 1.0, &[-0.5], &[1.0], &[]),
        ),
        (
            "double-pendulum".to_string(),
            mechanisms::double_pendulum(
                DoublePendulum {
                    m: [1.0, 1.0],
                    l: [1.0, 1.0],
                },
                [0.3, 1.0],
                [0.0, 2.0],
                [0.0, 0.0],
            ),
        ),
        ("four-bar".to_string(), mechanisms::four_bar(2.5, 1.0, 0.0, false)),
        ("slider-crank".to_string(), mechanisms::slider_crank(1.0, 3.0)),
    ];
    for n in [1usize, 4, 16, 64, 256, 1024, 4096] {
        v.push((format!("chain-{n}"), chain(n)));
    }
    v
}

fn evaluations(c: &mut Criterion) {
    let mut group = c.benchmark_group("evaluation");
    for (name, mech) in scenes() {
        for kind in ["augmented", "embedding", "amalgamated"] {
            // The embedding's reduced mass matrix of a chain is dense (N × N, Cholesky N³/6): above
            // 256 links the embedding and amalgamated formulations are out of their range
            // (docs/formulations.md).
            if kind != "augmented" && mech.q.len() > 3 * 256 {
                continue;
            }
            let mut f = formulation(kind, &mech);
            let (n, m) = (mech.q.len(), mech.model.num_equations());
            let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
            group.bench_with_input(BenchmarkId::new(kind, &name), &mech, |b, mech| {
                // A new time at every call (the scenes do not depend on it): the formulations keep
                // the constraint values of an unchanged state, which would skip their evaluation.
                let mut t = 0.0;
                b.iter(|| {
                    t += 1e-12;
                    f.accelerations(t, black_box(&mech.q), black_box(&mech.qd), None, &mut qdd, &mut lam)
                        .expect("evaluation");
                })
            });
        }
    }
    group.finish();
}

/// A system to evaluate: name, system, positions, velocities.
type Case = (
    &'static str,
    std::sync::Arc<dyn dalembert::system::MultibodySystem>,
    Vec<f64>,
    Vec<f64>,
);

/// chain3d of 16 and 64 links at a state with every joint turned and turning: the augmented
/// formulation in absolute coordinates and in joint coordinates (where every formulation is the
/// articulated-body algorithm).
fn spatial_chain(c: &mut Criterion) {
    let mut group = c.benchmark_group("spatial chain");
    for n in [16usize, 64] {
        let model = dalembert_testkit::spatial::chain3d(n);
        let jc = model.joint_coordinates().expect("chain3d is a tree");
        let th: Vec<f64> = (0..n).map(|k| 0.3 - 0.02 * k as f64).collect();
        let thd: Vec<f64> = (0..n).map(|k| 0.5 + 0.01 * k as f64).collect();
        let (mut q, mut v) = model.initial_state();
        jc.absolute(&th, &thd, &mut jc.frames(), &mut q, &mut v);
        let cases: [Case; 2] = [("absolute", model.clone(), q, v), ("joint", jc.system(), th, thd)];
        for (name, sys, q, v) in cases {
            let mut f = Augmented::with_defaults(sys.clone()).expect("augmented");
            let (mut qdd, mut lam) = (vec![0.0; v.len()], vec![0.0; sys.num_equations()]);
            group.bench_function(BenchmarkId::new(name, format!("chain3d-{n}")), |b| {
                let mut t = 0.0;
                b.iter(|| {
                    t += 1e-12;
                    f.accelerations(t, black_box(&q), black_box(&v), None, &mut qdd, &mut lam)
                        .expect("evaluation");
                })
            });
        }
    }
    group.finish();
}

/// Median time of one augmented evaluation on a chain of `n` links, and the back end `Auto` chose.
fn time_per_evaluation(n: usize) -> (f64, &'static str) {
    let mech = chain(n);
    let mut f = Augmented::with_defaults(mech.model.clone()).expect("augmented");
    let (mut qdd, mut lam) = (vec![0.0; mech.q.len()], vec![0.0; mech.model.num_equations()]);
    let reps = (200_000 / n).max(5);
    let mut samples: Vec<f64> = (0..7)
        .map(|_| {
            let t0 = Instant::now();
            for k in 0..reps {
                // A new time at every call, as above.
                f.accelerations(1e-12 * k as f64, &mech.q, &mech.qd, None, &mut qdd, &mut lam)
                    .expect("evaluation");
            }
            t0.elapsed().as_secs_f64() / reps as f64
        })
        .collect();
    samples.sort_by(|a, b| a.total_cmp(b));
    (samples[3], f.backend_name())
}

fn scaling() {
    let ns = [16usize, 64, 256, 1024, 4096];
    let runs: Vec<(f64, &str)> = ns.iter().map(|&n| time_per_evaluation(n)).collect();
    let times: Vec<f64> = runs.iter().map(|r| r.0).collect();
    let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = times.iter().map(|t| t.ln()).collect();
    let k = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / k, ys.iter().sum::<f64>() / k);
    let slope = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    println!("\naugmented formulation, one evaluation on a chain of N rods (back end chosen by Auto):");
    for (n, (t, backend)) in ns.iter().zip(&runs) {
        println!(
            "  N = {n:5}: {:10.2} µs  ({:.3} µs per body, {backend})",
            t * 1e6,
            t * 1e6 / *n as f64
        );
    }
    println!("  fitted exponent of cost against N (16 … 4096): {slope:.3}");
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    evaluations(&mut c);
    spatial_chain(&mut c);
    c.final_summary();
    scaling();
}
