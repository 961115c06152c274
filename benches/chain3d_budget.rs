//! Where the time of the spatial chain's RK4 run goes (`shared/anchors`' `chain3d`, the spatial
//! issue's target scene): for N = 16 and 64, the whole run (10 s at 1 ms, four evaluations per
//! step), one `Augmented::accelerations`, and its two parts that the formulation cannot share with
//! anything else: the constraint evaluation (`C`, `C_q`, `γ` of every joint) and the factorization
//! and solve of the saddle-point system (the back end `Auto` chooses: the tree). What is left of
//! the run per evaluation once the factorization and solve are taken away is the floor that no
//! faster linear algebra can go under; with `ANCHORS_MUJOCO_RK4_S` (MuJoCo's RK4 time for
//! chain3d-64 from the same machine's anchors run) it also prints what a factorization and solve
//! would have to cost for the run to take no longer than MuJoCo's.
//!
//! `cargo bench --bench chain3d_budget` (about 10 s); `ANCHORS_MUJOCO_RK4_S=0.645 cargo bench …`.

use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::system::linalg::{Backend, SaddlePoint};
use dalembert::system::Formulation;
use dalembert::system::{BlockDiagonal, ConstraintSet, MultibodySystem};
use std::hint::black_box;
use std::time::Instant;

/// Median of `runs` timings of `f` repeated `reps` times, per repetition, in µs.
fn median_us(runs: usize, reps: usize, mut f: impl FnMut(usize)) -> f64 {
    let mut samples: Vec<f64> = (0..runs)
        .map(|_| {
            let t0 = Instant::now();
            for k in 0..reps {
                f(k);
            }
            t0.elapsed().as_secs_f64() * 1e6 / reps as f64
        })
        .collect();
    samples.sort_by(|a, b| a.total_cmp(b));
    samples[runs / 2]
}

fn main() {
    let mujoco: Option<f64> = std::env::var("ANCHORS_MUJOCO_RK4_S").ok().and_then(|s| s.parse().ok());
    for n in [16usize, 64] {
        let model = dalembert_testkit::spatial::chain3d(n);
        let (q0, v0) = model.initial_state();
        let rk4 = |end: f64| IntegratorOptions::fixed(Method::rk4(), 1e-3, end);
        // The whole run, as the anchors time it (median of 3).
        let mut runs: Vec<f64> = (0..3)
            .map(|_| {
                let mut f = Augmented::with_defaults(model.clone()).expect("chain3d");
                let t0 = Instant::now();
                integrate(&mut f, 0.0, 10.0, &q0, &v0, &rk4(0.01), &mut |_| {}).expect("run");
                t0.elapsed().as_secs_f64()
            })
            .collect();
        runs.sort_by(|a, b| a.total_cmp(b));
        let run_s = runs[1];
        let per_eval_us = run_s * 1e6 / 40_000.0;
        // A state inside the run (0.7 s of the fall: no joint at its initial angle).
        let mut f = Augmented::with_defaults(model.clone()).expect("chain3d");
        let (mut q, mut v) = (q0.clone(), v0.clone());
        integrate(&mut f, 0.0, 0.7, &q0, &v0, &rk4(0.7), &mut |s| {
            q.copy_from_slice(s.q);
            v.copy_from_slice(s.qd);
        })
        .expect("run");
        let sys: &dyn ConstraintSet = model.constraints();
        let (nv, m) = (v.len(), sys.num_equations());
        let (mut qdd, mut lam) = (vec![0.0; nv], vec![0.0; m]);
        let reps = 200_000 / n;
        // A new time at every call: an unchanged state would reuse the constraint values.
        let accelerations_us = median_us(7, reps, |k| {
            f.accelerations(
                0.7 + 1e-12 * k as f64,
                black_box(&q),
                black_box(&v),
                None,
                &mut qdd,
                &mut lam,
            )
            .expect("evaluation");
        });
        let mut values = sys.values();
        let evaluate_us = median_us(7, reps, |k| {
            sys.evaluate(0.7 + 1e-12 * k as f64, black_box(&q), &v, &mut values)
        });
        let mut mass = BlockDiagonal::zeros(vec![6; n]);
        model.mass(&q, &mut mass);
        let mut b = vec![0.0; nv + m];
        model.applied_forces(0.7, &q, &v, &mut b[..nv]);
        b[nv..].copy_from_slice(&values.gamma);
        let mut kkt = SaddlePoint::new(Backend::Auto, &mass, true, sys, 10_000, 1e-13).expect("back end");
        let mut x = b.clone();
        let solve_us = median_us(7, reps, |_| {
            x.copy_from_slice(&b);
            kkt.factor(&mass, sys.pattern(), &values).expect("factor");
            kkt.solve(sys.pattern(), black_box(&mut x));
        });
        // The same solution as the formulation's: the accelerations agree to rounding.
        let dx = qdd.iter().zip(&x).map(|(a, b)| (a - b).abs()).fold(0.0f64, f64::max);
        let floor_us = per_eval_us - solve_us;
        println!("chain3d-{n} ({} back end):", kkt.name());
        println!("  RK4 10 s at 1 ms: {run_s:.3} s = {per_eval_us:.2} µs per evaluation");
        println!("  one accelerations call:        {accelerations_us:7.2} µs");
        println!("    constraint evaluation:       {evaluate_us:7.2} µs");
        println!("    factorization and solve:     {solve_us:7.2} µs   (max |Δq̈| against the call {dx:.1e})");
        println!(
            "  run per evaluation without the factorization and solve: {floor_us:.2} µs ({:.3} s per run)",
            floor_us * 0.04
        );
        if let (Some(s), 64) = (mujoco, n) {
            let budget = s * 1e6 / 40_000.0 - floor_us;
            println!(
                "  MuJoCo RK4 {s:.3} s = {:.2} µs per evaluation: a factorization and solve of at most {budget:.2} µs \
                 ({:.0} ns per link) would match it, {:.1}× faster than this one",
                s * 1e6 / 40_000.0,
                budget * 1e3 / n as f64,
                solve_us / budget
            );
        }
    }
}
