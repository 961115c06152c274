//! The friction forces of one evaluation (`docs/friction.md`, "Cost"): the slipping joints'
//! forces are found by iterating on them together (one solve per iteration), the holding joints'
//! by Newton's method on their responses, and Newton's method on every joint takes over where
//! the iteration contracts too slowly. Whatever the path, the forces must solve Coulomb's law at
//! the multipliers the evaluation returns, and the accelerations must be the frictionless
//! model's under those forces, evaluated separately here.

use dalembert::system::SlipRow;
use dalembert::Scene;
use dalembert_testkit::chain_scene::planar_chain_toml;

const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];

/// A horizontal chain of six rods (1 kg, 1 m) pinned end to end and to the ground, each link
/// turning at `omegas[k]` (the joints' rates are their differences), with pin friction `mu`,
/// `r` on every joint, or none.
fn chain(formulation: &str, friction: Option<(f64, f64)>, omegas: &[f64]) -> Scene {
    let mut text = planar_chain_toml(omegas.len(), friction);
    text += &format!("[simulation]\nformulation = \"{formulation}\"\n[initial.velocities]\n");
    for (k, w) in omegas.iter().enumerate() {
        text += &format!("\"link{k}.omega\" = {w}\n");
    }
    Scene::from_toml(&text, "chain").unwrap()
}

/// The largest residual of each law, relative to its scale, at the start of `chain` with
/// friction `(mu, r)`: (slipping joints' `F + σ μ r |F_pin|`, stuck joints' slip acceleration,
/// the accelerations against the frictionless model's under the forces found, the multipliers
/// likewise); and how many joints slip, are held at rest, and begin to slip from rest.
fn residuals(formulation: &str, (mu, r): (f64, f64), omegas: &[f64]) -> ([f64; 4], [usize; 3]) {
    let sim = chain(formulation, Some((mu, r)), omegas).simulation();
    let mut f = sim.formulation().unwrap();
    let (n, m) = (f.system().layout().n_v(), f.system().num_equations());
    let (mut qdd, mut lambda) = (vec![0.0; n], vec![0.0; m]);
    f.start_events(0.0, &sim.q, &sim.qd);
    f.accelerations(0.0, &sim.q, &sim.qd, None, &mut qdd, &mut lambda)
        .unwrap();
    let forces = f.friction_forces().to_vec();
    let system = f.system();
    let largest = |x: &[f64]| x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let (a_scale, l_scale) = (largest(&qdd).max(1.0), largest(&lambda));
    let mut extra = vec![0.0; n];
    let (mut law, mut stuck_rate, mut slipping, mut held, mut starting) = (0.0f64, 0.0f64, 0, 0, 0);
    for (k, spec) in system.frictions().iter().enumerate() {
        let mut row = SlipRow::default();
        system.slip_row(k, 0.0, &sim.q, &sim.qd, &mut row);
        for &(i, g) in row.entries() {
            extra[i] += g * forces[k];
        }
        let w = row.dot(&sim.qd);
        let load = spec
            .load_rows
            .iter()
            .map(|&i| lambda[i] * lambda[i])
            .sum::<f64>()
            .sqrt();
        let bound = spec.coefficient * load;
        if w.abs() > spec.stick_speed {
            slipping += 1;
            law = law.max((forces[k] + w.signum() * bound).abs() / bound);
        } else {
            // Held ((F2): no slip acceleration, the force within the bound), or slipping from
            // rest ((F3): the force at the bound, against the slip acceleration).
            let rate = row.dot(&qdd) + row.bias;
            if forces[k].abs() < bound * (1.0 - 1e-12) {
                held += 1;
                stuck_rate = stuck_rate.max(rate.abs() / a_scale);
            } else {
                starting += 1;
                law = law.max((forces[k].abs() - bound).abs() / bound);
                assert!(
                    forces[k] * rate <= 0.0,
                    "{formulation}: J{k} friction {} along its slip {rate}",
                    forces[k]
                );
            }
        }
    }
    // The same chain without friction, the forces found applied as generalized forces.
    let plain = chain(formulation, None, omegas).simulation();
    let mut g = plain.formulation().unwrap();
    assert!(g.set_extra_force(Some(&extra)), "{formulation} takes an added force");
    let (mut qdd2, mut lambda2) = (vec![0.0; n], vec![0.0; m]);
    g.accelerations(0.0, &sim.q, &sim.qd, None, &mut qdd2, &mut lambda2)
        .unwrap();
    let differs = |x: &[f64], y: &[f64], s: f64| x.iter().zip(y).fold(0.0f64, |a, (u, v)| a.max((u - v).abs())) / s;
    (
        [
            law,
            stuck_rate,
            differs(&qdd, &qdd2, a_scale),
            differs(&lambda, &lambda2, l_scale),
        ],
        [slipping, held, starting],
    )
}

#[test]
fn the_forces_of_slipping_and_stuck_joints_solve_coulombs_law_with_the_formulation() {
    // Four joints slip (rates 0.7, −1.1, 1.5, −0.9 rad/s), two start from rest; the friction
    // couples them through the pin forces. Three strengths: μ r = 0.015 m (the iteration on the
    // slipping joints contracts by about 2e-3 per solve; both joints at rest begin to slip),
    // 0.3 m (one is held) and 0.49 m (measured: the iteration contracts by less than half and
    // Newton's method on every joint decides). Each law holds to 1e-12 of its scale (the
    // iteration stops where what it leaves is below 1e-15 of the largest force; measured 5e-14
    // at most, on the weakest joint's bound), and the accelerations and multipliers are the
    // frictionless model's under those forces to 1e-12 (two solves of one system: measured
    // 1.6e-15 at most).
    let omegas = [0.7, -0.4, -0.4, 1.1, 0.2, 0.2];
    for (friction, counts) in [
        ((0.3, 0.05), [4, 0, 2]),
        ((0.6, 0.5), [4, 1, 1]),
        ((0.7, 0.7), [4, 1, 1]),
    ] {
        for formulation in FORMULATIONS {
            let (r, found) = residuals(formulation, friction, &omegas);
            assert_eq!(
                found, counts,
                "{formulation}, {friction:?}: joints slipping, held, starting"
            );
            for (what, value) in ["slip law", "stuck rate", "accelerations", "multipliers"].iter().zip(r) {
                assert!(value <= 1e-12, "{formulation}, {friction:?}: {what} off by {value:.2e}");
            }
        }
    }
}

#[test]
fn a_friction_the_law_does_not_determine_is_named() {
    // μ r = 0.81 m on 1 m links: the first pin's friction changes its own load by more than
    // itself (μ |L Λ| = 1.018 ≥ 1, Painlevé), so Coulomb's law has no unique force. The
    // evaluation is an error naming the joint, on every formulation.
    let omegas = [0.7, -0.4, -0.4, 1.1, 0.2, 0.2];
    for formulation in FORMULATIONS {
        let sim = chain(formulation, Some((0.9, 0.9)), &omegas).simulation();
        let mut f = sim.formulation().unwrap();
        let (n, m) = (f.system().layout().n_v(), f.system().num_equations());
        let (mut qdd, mut lambda) = (vec![0.0; n], vec![0.0; m]);
        f.start_events(0.0, &sim.q, &sim.qd);
        let message = f
            .accelerations(0.0, &sim.q, &sim.qd, None, &mut qdd, &mut lambda)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("'J0'") && message.contains("Painlevé"),
            "{formulation}: {message}"
        );
    }
}
