//! Long-run accuracy against the exact pendulum, constraint drift with each treatment, and
//! blow-up of an explicit step beyond its stability limit.

mod common;
use common::run;

use dalembert_augmented::Augmented;
use dalembert_integrators::{integrate, IntegrationError, IntegratorOptions, Method, Stabilization};
use dalembert_system::Baumgarte;
use dalembert_testkit::closed_form::pendulum_angle;
use dalembert_testkit::mechanisms::{self, G};

/// A rod pendulum (L = 1 m) released from rest 60° from the vertical, RK4 at h = 1 ms for 2000 s
/// (≈ 1300 periods): the angle stays within 1e-3 rad of the elliptic-function solution.
#[test]
fn pendulum_2000_s_matches_elliptic_solution() {
    let l = 1.0;
    let phi0 = std::f64::consts::FRAC_PI_3;
    let mech = mechanisms::chain(1.0, l, &[phi0 - std::f64::consts::FRAC_PI_2], &[0.0], &[]);
    let omega0 = (1.5 * G / l).sqrt(); // rod about its end: m g L/2 / (m L²/3)
    let t_end = 2000.0;
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, t_end);
    let (q, _, stats) = run(&mech, t_end, &opts).unwrap();
    let phi = q[2] + std::f64::consts::FRAC_PI_2;
    let exact = pendulum_angle(phi0, omega0, t_end);
    assert!((phi - exact).abs() < 1e-3, "φ = {phi}, exact {exact}");
    // RK4 dissipates ≈ (hω₀)⁵ of the energy per step and the unstabilized constraint drift adds to
    // it; the measured drift is ≈ 7e-5 J. Bound: 1e-4 of m g L (≈ 1e-3 J).
    assert!(
        stats.max_energy_change < 1e-4 * G * l,
        "energy drift {}",
        stats.max_energy_change
    );
}

/// Four-bar released from rest for 10 s with semi-implicit Euler at h = 1 ms (first order, so the
/// drift is visible): no treatment → |C| grows (last 2 s ≥ 3× the first 2 s); Baumgarte → bounded
/// (last 2 s no worse than 2× the first 2 s) and far below the unstabilized drift; projection → at
/// the Newton tolerance 1e-10 after every step.
#[test]
fn four_bar_drift_with_each_treatment() {
    let mech = mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false);
    let h = 1e-3;
    let t_end = 10.0;
    let base = IntegratorOptions::fixed(Method::symplectic_euler(), h, 0.01);
    let violations = |treatment| {
        let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
        let mut early = 0.0f64;
        let mut late = 0.0f64;
        let stats = integrate(
            &mut f,
            0.0,
            t_end,
            &mech.q,
            &mech.qd,
            &base.with_stabilization(treatment),
            &mut |s| {
                if s.t <= 2.0 {
                    early = early.max(s.constraint_violation);
                }
                if s.t >= t_end - 2.0 {
                    late = late.max(s.constraint_violation);
                }
            },
        )
        .unwrap();
        (early, late, stats)
    };
    let (e0, l0, none) = violations(Stabilization::None);
    assert!(
        l0 >= 3.0 * e0 && l0 > 1e-6,
        "no treatment: first 2 s {e0:e}, last 2 s {l0:e}"
    );
    let (e1, l1, baum) = violations(Stabilization::BaumgarteGains(Baumgarte::for_step(h)));
    assert!(
        l1 <= 2.0 * e1.max(1e-12),
        "Baumgarte grows: first 2 s {e1:e}, last 2 s {l1:e}"
    );
    assert!(
        baum.max_constraint_violation < 0.1 * none.max_constraint_violation,
        "Baumgarte {:e} vs none {:e}",
        baum.max_constraint_violation,
        none.max_constraint_violation
    );
    let (_, _, proj) = violations(Stabilization::Projection { tolerance: 1e-10 });
    assert!(
        proj.max_constraint_violation <= 1e-10,
        "projection {}",
        proj.max_constraint_violation
    );
    assert!(
        proj.max_velocity_violation <= 1e-10,
        "projection Ċ {}",
        proj.max_velocity_violation
    );
    assert!(proj.newton_iterations > 0);
}

/// A 1 kg slider on a 1e8 N/m spring (ω = 1e4 rad/s): RK4 at h = 1 ms (hω = 10, far beyond its
/// limit 2.8) stops with a divergence error naming the time; every sample observed is finite.
#[test]
fn explicit_step_beyond_stability_limit_is_an_error() {
    let mech = mechanisms::slider_on_spring(1e8);
    let q = mech.q.clone();
    let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
    let mut all_finite = true;
    let err = integrate(
        &mut f,
        0.0,
        1.0,
        &q,
        &[0.0; 3],
        &IntegratorOptions::fixed(Method::rk4(), 1e-3, 1e-3),
        &mut |s| {
            all_finite &= s.q.iter().chain(s.qd).all(|x| x.is_finite());
        },
    )
    .unwrap_err();
    assert!(matches!(err.error, IntegrationError::Diverged { .. }), "{err}");
    assert!(all_finite);
    assert!(err.statistics.steps > 0);
    // A step well inside the limit (hω = 0.1) runs; RK4 then loses ≈ (hω)⁶/144 ≈ 7e-9 of the
    // 50 J spring energy per step, ≈ 7e-6 over 1000 steps: bound 1e-4 of it.
    let ok = integrate(
        &mut f,
        0.0,
        0.01,
        &q,
        &[0.0; 3],
        &IntegratorOptions::fixed(Method::rk4(), 1e-5, 1e-3),
        &mut |_| {},
    )
    .unwrap();
    assert!(ok.max_energy_change < 1e-4 * 50.0, "{}", ok.max_energy_change);
}
