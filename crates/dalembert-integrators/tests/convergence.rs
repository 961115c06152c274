//! Convergence order of the fixed-step methods on the double pendulum, and accuracy of the adaptive
//! method against its tolerance.
//!
//! Reference: RK4 with h = 1/8000 s. RK4's measured error constant here is C ≈ 7e5 (error 2.8e-6
//! at h = 1/800), so the reference is good to ≈ 3e-10, 500× below the smallest error fitted.
//! Error at t = 1 s: max over positions and velocities. The slope of log(error) against log(h) must
//! lie within ±0.3 of the method's order.

mod common;
use common::{max_diff, run};
use dalembert_integrators::{IntegratorOptions, Method};
use dalembert_testkit::closed_form::DoublePendulum;
use dalembert_testkit::mechanisms;

fn mech() -> dalembert_testkit::Mechanism {
    mechanisms::double_pendulum(
        DoublePendulum {
            m: [1.0, 1.0],
            l: [1.0, 1.0],
        },
        [0.3, 1.0],
        [0.0, 2.0],
        [0.0, 0.0],
    )
}

fn reference() -> Vec<f64> {
    let (q, qd, _) = run(
        &mech(),
        1.0,
        &IntegratorOptions::fixed(Method::rk4(), 1.0 / 8000.0, 1.0),
    )
    .unwrap();
    [q, qd].concat()
}

fn slope(method: Method, steps: &[f64], reference: &[f64]) -> (f64, Vec<f64>) {
    let errs: Vec<f64> = steps
        .iter()
        .map(|&h| {
            let (q, qd, _) = run(&mech(), 1.0, &IntegratorOptions::fixed(method, h, 1.0)).unwrap();
            max_diff(&[q, qd].concat(), reference)
        })
        .collect();
    let n = steps.len() as f64;
    let xs: Vec<f64> = steps.iter().map(|h| h.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    (num / den, errs)
}

#[test]
fn fixed_step_methods_converge_at_their_order() {
    let reference = reference();
    let (p_euler, e1) = slope(
        Method::symplectic_euler(),
        &[1.0 / 200.0, 1.0 / 400.0, 1.0 / 800.0, 1.0 / 1600.0],
        &reference,
    );
    assert!(
        (p_euler - 1.0).abs() <= 0.3,
        "symplectic Euler slope {p_euler} (errors {e1:?})"
    );
    let (p_rk4, e4) = slope(
        Method::rk4(),
        &[1.0 / 100.0, 1.0 / 200.0, 1.0 / 400.0, 1.0 / 800.0],
        &reference,
    );
    assert!((p_rk4 - 4.0).abs() <= 0.3, "RK4 slope {p_rk4} (errors {e4:?})");
}

/// Dormand–Prince: the error at t = 1 s follows the tolerance (within a factor 100 of rtol for the
/// state of size ≈ 1–5), and tightening the tolerance by 10³ shrinks it.
#[test]
fn dormand_prince_meets_its_tolerance() {
    let reference = reference();
    let mut last = f64::INFINITY;
    for &tol in &[1e-6, 1e-9] {
        let opts = IntegratorOptions::fixed(Method::dopri5(tol, tol), 1e-3, 0.1);
        let (q, qd, stats) = run(&mech(), 1.0, &opts).unwrap();
        let err = max_diff(&[q, qd].concat(), &reference);
        assert!(err < 100.0 * tol, "tol {tol}: error {err}");
        assert!(err < last / 10.0, "tol {tol}: error {err} did not shrink from {last}");
        assert!(stats.steps > 5 && stats.evaluations >= 6 * stats.steps);
        last = err;
    }
}

/// Dense output between steps is as accurate as the steps themselves: outputs every 10 ms from a
/// run with few, long steps match the reference run's outputs.
#[test]
fn dormand_prince_dense_output_is_accurate() {
    let m = mech();
    let collect = |opts: IntegratorOptions| {
        let mut f = dalembert_augmented::Augmented::with_defaults(m.model.clone()).unwrap();
        let mut out = Vec::new();
        dalembert_integrators::integrate(&mut f, 0.0, 0.5, &m.q, &m.qd, &opts, &mut |s| {
            out.push((s.t, s.q.to_vec()))
        })
        .unwrap();
        out
    };
    let coarse = collect(IntegratorOptions {
        max_step: 0.5,
        ..IntegratorOptions::fixed(Method::dopri5(1e-8, 1e-8), 1e-2, 0.01)
    });
    let fine = collect(IntegratorOptions::fixed(Method::rk4(), 1e-4, 0.01));
    assert_eq!(coarse.len(), fine.len());
    for ((t1, a), (t2, b)) in coarse.iter().zip(&fine) {
        assert!((t1 - t2).abs() < 1e-12);
        assert!(max_diff(a, b) < 1e-6, "t = {t1}: {}", max_diff(a, b));
    }
}
