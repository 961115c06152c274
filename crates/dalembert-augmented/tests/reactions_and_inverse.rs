//! Reactions against free-body diagrams, and inverse dynamics against closed forms and the power
//! balance.

use dalembert_augmented::{Augmented, InverseDynamics};
use dalembert_constraints::Reaction;
use dalembert_kinematics::Vec2;
use dalembert_system::{ConstraintSet as _, MultibodySystem as _};
use dalembert_system::{Formulation, KinematicOptions};
use dalembert_testkit::closed_form::DoublePendulum;
use dalembert_testkit::mechanisms::{self, Mechanism, G};

fn forward(mech: &Mechanism) -> (Vec<f64>, Vec<f64>, Vec<Reaction>) {
    let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
    let (n, m) = (mech.q.len(), mech.model.num_equations());
    let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
    f.accelerations(0.0, &mech.q, &mech.qd, None, &mut qdd, &mut lam)
        .unwrap();
    let sys = mech.model.constraints();
    let mut vals = sys.values();
    sys.evaluate(0.0, &mech.q, &mech.qd, &mut vals);
    let mut r = vec![Reaction::default(); sys.constraints().len()];
    sys.reactions(&mech.q, &vals, &lam, &mut r);
    (qdd, lam, r)
}

/// Point mass on a string: the string tension is `m (φ̇² L + g cos φ)` (radial free-body diagram of
/// the bob), and the pivot is pulled towards the bob. Tolerance 1e-12 relative (round-off).
#[test]
fn pendulum_string_tension_from_free_body_diagram() {
    let (m, l) = (0.8, 1.3);
    for &(phi, phi_dot) in &[(0.0, 0.0), (0.6, 0.0), (-1.1, 2.2), (2.5, -3.0)] {
        let mech = mechanisms::point_pendulum(m, l, phi, phi_dot);
        let (_, _, r) = forward(&mech);
        let tension = m * (phi_dot * phi_dot * l + G * phi.cos());
        let e = Vec2::new(phi.sin(), -phi.cos()); // pivot → bob
        let expected = e * tension; // force on the ground (first body) from the bob (second)
        assert!(
            (r[0].force - expected).norm() < 1e-12 * (1.0 + tension.abs()),
            "{:?} vs {expected:?}",
            r[0].force
        );
        assert!(r[0].torque.abs() < 1e-12, "a pin carries no torque");
    }
}

/// Rod pendulum: Newton's law on the rod gives the pin force on it, `R = m (a_cm − g)`; the
/// reported reaction (on the ground, from the rod) is `−R`. At rest hanging down it is the weight.
#[test]
fn rod_pendulum_reaction_balances_newtons_law() {
    let (m, l) = (2.0, 1.0);
    let hang = mechanisms::chain(m, l, &[-std::f64::consts::FRAC_PI_2], &[0.0], &[]);
    let (_, _, r) = forward(&hang);
    assert!((r[0].force - Vec2::new(0.0, -m * G)).norm() < 1e-12 * m * G);
    for &(th, w) in &[(0.4, 0.0), (-2.0, 3.0)] {
        let mech = mechanisms::chain(m, l, &[th], &[w], &[]);
        let (qdd, _, r) = forward(&mech);
        let on_rod = Vec2::new(m * qdd[0], m * qdd[1] + m * G);
        assert!(
            (r[0].force + on_rod).norm() < 1e-12 * m * G,
            "{:?} vs {:?}",
            r[0].force,
            -on_rod
        );
        // Moment balance about the centre of mass: J α = (pin − cm) × R.
        let arm = Vec2::new(-th.cos(), -th.sin()) * (l / 2.0);
        let moment = arm.x * on_rod.y - arm.y * on_rod.x;
        assert!((m * l * l / 12.0 * qdd[2] - moment).abs() < 1e-12 * m * G * l);
    }
}

/// Two-link arm with both joint angles prescribed: the driver efforts equal the closed-form joint
/// torques `M(θ)θ̈ + h(θ, θ̇) + g(θ)` at every sample. Tolerance 1e-10 relative: kinematic analysis
/// converges to 1e-12 in angle, and torques of ≈ 10–50 N·m inherit that with factor ≈ 10–100.
#[test]
fn two_link_inverse_dynamics_matches_closed_form_torques() {
    let (m, l) = ([3.0, 1.2], [0.8, 0.6]);
    let p1 = vec![0.3, 1.2, -0.5, 0.1];
    let p2 = vec![0.9, -0.7, 0.8];
    let mech = mechanisms::driven_two_link(m, l, p1.clone(), p2.clone());
    let inv = InverseDynamics::new(mech.model.clone(), &mech.q, KinematicOptions::default()).unwrap();
    let dp = DoublePendulum { m, l };
    let poly = |c: &[f64], t: f64| dalembert_system::TimeFunction::Polynomial(c.to_vec()).eval(t);
    let mut q = mech.q.clone();
    for k in 0..=20 {
        let t = 0.1 * k as f64;
        let sol = inv.solve(t, &q).unwrap();
        q = sol.q.clone();
        let (a, b) = (poly(&p1, t), poly(&p2, t));
        let th = [a[0], a[0] + b[0]];
        let w = [a[1], a[1] + b[1]];
        let acc = [a[2], a[2] + b[2]];
        let tau = dp.joint_torques(th, w, acc);
        let reactions = mech.model.constraints().reactions_at(t, &sol.q, &sol.lambda);
        let efforts = [reactions[2].effort.unwrap(), reactions[3].effort.unwrap()];
        for j in 0..2 {
            assert!(
                (efforts[j] - tau[j]).abs() < 1e-10 * (1.0 + tau[j].abs()),
                "t={t} joint {j}: {} vs {}",
                efforts[j],
                tau[j]
            );
        }
    }
}

/// Four-bar with the crank angle prescribed at constant speed: the motor's power equals the rate of
/// change of the total energy, `τ φ̇ = q̇ᵀ M q̈ + g Σ m_k ẏ_k` (joints do no work), at every sample.
/// Tolerance 1e-9 relative to the largest power of the run.
#[test]
fn four_bar_inverse_dynamics_power_balance() {
    let phi_dot = 2.0;
    let mech = mechanisms::four_bar(std::f64::consts::PI, phi_dot, 0.0, true);
    let model = mech.model.clone();
    let inv = InverseDynamics::new(model.clone(), &mech.q, KinematicOptions::default()).unwrap();
    let mut q = mech.q.clone();
    let mut samples = Vec::new();
    for k in 0..=60 {
        let t = 0.05 * k as f64;
        let sol = inv.solve(t, &q).unwrap();
        q = sol.q.clone();
        let mut mqdd = vec![0.0; q.len()];
        model.mass_matrix(&sol.q).mul_add(1.0, &sol.qdd, &mut mqdd);
        let kinetic_rate: f64 = sol.qd.iter().zip(&mqdd).map(|(a, b)| a * b).sum();
        let potential_rate: f64 = model
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| b.mass * G * sol.qd[3 * i + 1])
            .sum();
        let motor = model.constraints().reactions_at(t, &sol.q, &sol.lambda)[4]
            .effort
            .unwrap()
            * phi_dot;
        samples.push((motor, kinetic_rate + potential_rate));
    }
    let scale = samples.iter().fold(0.0f64, |a, s| a.max(s.0.abs()));
    assert!(scale > 1.0, "the test must exercise real power");
    for (i, (motor, rate)) in samples.iter().enumerate() {
        assert!(
            (motor - rate).abs() <= 1e-9 * scale,
            "sample {i}: motor {motor} vs dE/dt {rate}"
        );
    }
}

#[test]
fn inverse_dynamics_refuses_an_underdriven_model() {
    let mech = mechanisms::four_bar(3.0, 0.0, 0.0, false);
    let err = InverseDynamics::new(mech.model.clone(), &mech.q, KinematicOptions::default()).unwrap_err();
    assert!(err.to_string().contains("1 degrees of freedom"), "{err}");
}
