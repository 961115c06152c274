//! Generalized-α keeps second order as the step shrinks: the Newton stopping test is scaled to the
//! step and the state, so small steps do not stop after one inexact iteration (issue: error
//! ratio between h and h/2 at least 3.5 over five halvings down to h = 1e-5, on a pendulum).

mod common;
use common::{max_diff, run};
use dalembert_integrators::{IntegratorOptions, Method, Stabilization};
use dalembert_testkit::mechanisms;

#[test]
fn second_order_down_to_ten_microseconds() {
    // A uniform rod (1 kg, 1 m) pinned at one end, released horizontally, 2 s.
    let mech = mechanisms::chain(1.0, 1.0, &[0.0], &[0.0], &[0.0]);
    let t_end = 2.0;
    // Reference: RK4 with projection at h = 2.5e-5 (error ≈ 1e-15, far below the GA errors).
    let (qr, qdr, _) = run(
        &mech,
        t_end,
        &IntegratorOptions::fixed(Method::rk4(), 2.5e-5, t_end)
            .with_stabilization(Stabilization::Projection { tolerance: 1e-13 }),
    )
    .unwrap();
    let reference = [qr, qdr].concat();
    let steps = [3.2e-4, 1.6e-4, 8e-5, 4e-5, 2e-5, 1e-5];
    let errs: Vec<f64> = steps
        .iter()
        .map(|&h| {
            let (q, qd, s) = run(
                &mech,
                t_end,
                &IntegratorOptions::fixed(Method::generalized_alpha(0.8), h, t_end),
            )
            .unwrap();
            eprintln!(
                "h = {h:e}: iterations per step {:.2}",
                s.newton_iterations as f64 / s.steps as f64
            );
            max_diff(&[q, qd].concat(), &reference)
        })
        .collect();
    eprintln!("errors {errs:?}");
    for w in errs.windows(2) {
        assert!(
            w[0] / w[1] >= 3.5,
            "ratios {:?}",
            errs.windows(2).map(|w| w[0] / w[1]).collect::<Vec<_>>()
        );
    }
}
