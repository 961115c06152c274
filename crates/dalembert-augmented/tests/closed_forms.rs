//! The augmented solve against minimal-coordinate closed forms derived independently
//! (`dalembert-testkit::closed_form`), on every back end (dense LU, Schur complement, sparse LU).
//!
//! Tolerance 1e-12 relative: the saddle-point systems here have condition numbers ≈ 1e2–1e3, so
//! backward-stable LU leaves ≈ 1e-14 relative error; 1e-12 leaves a margin without hiding a
//! wrong term (any modelling error is O(1)).

use dalembert_augmented::{Augmented, AugmentedOptions, Backend};
use dalembert_system::Formulation;
use dalembert_system::MultibodySystem as _;
use dalembert_testkit::closed_form::{DoublePendulum, FourBar};
use dalembert_testkit::mechanisms::{self, Mechanism, G};

fn solve(mech: &Mechanism, backend: Backend) -> (Vec<f64>, Vec<f64>) {
    let opts = AugmentedOptions {
        backend,
        ..Default::default()
    };
    let mut f = Augmented::new(mech.model.clone(), opts).unwrap();
    let n = mech.q.len();
    let m = mech.model.num_equations();
    let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
    f.accelerations(0.0, &mech.q, &mech.qd, None, &mut qdd, &mut lam)
        .unwrap();
    (qdd, lam)
}

fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale.max(b.abs())
}

const BACKENDS: [Backend; 4] = [Backend::Dense, Backend::Schur, Backend::Sparse, Backend::SparseSchur];

#[test]
fn rod_pendulum_matches_closed_form() {
    // (m L²/3) θ̈ = −m g (L/2) cos θ, for a rod pinned at one end.
    let (m, l) = (2.0, 1.5);
    for &(th, w) in &[(0.3, 0.0), (-1.2, 2.5), (2.0, -4.0)] {
        let mech = mechanisms::chain(m, l, &[th], &[w], &[]);
        let alpha = -m * G * (l / 2.0) * th.cos() / (m * l * l / 3.0);
        let (s, c) = th.sin_cos();
        let ax = -(l / 2.0) * (s * alpha + c * w * w);
        let ay = (l / 2.0) * (c * alpha - s * w * w);
        for be in BACKENDS {
            let (qdd, _) = solve(&mech, be);
            let scale = G;
            assert!(rel(qdd[2], alpha, scale) < 1e-12, "{be:?} α {} vs {alpha}", qdd[2]);
            assert!(
                rel(qdd[0], ax, scale) < 1e-12 && rel(qdd[1], ay, scale) < 1e-12,
                "{be:?}"
            );
        }
    }
}

#[test]
fn double_pendulum_matches_closed_form() {
    let dp = DoublePendulum {
        m: [1.0, 2.5],
        l: [1.0, 0.7],
    };
    for &(th, w) in &[
        ([0.1, -0.4], [0.0, 0.0]),
        ([1.3, 2.9], [3.0, -5.0]),
        ([-2.0, 0.5], [-1.0, 7.0]),
    ] {
        let mech = mechanisms::double_pendulum(dp, th, w, [0.0, 0.0]);
        let acc = dp.accelerations(th, w, [0.0, 0.0]);
        for be in BACKENDS {
            let (qdd, _) = solve(&mech, be);
            assert!(rel(qdd[2], acc[0], 10.0) < 1e-12, "{be:?} {} vs {}", qdd[2], acc[0]);
            assert!(rel(qdd[5], acc[1], 10.0) < 1e-12, "{be:?} {} vs {}", qdd[5], acc[1]);
        }
    }
}

#[test]
fn two_link_manipulator_with_joint_torques_matches_closed_form() {
    let dp = DoublePendulum {
        m: [3.0, 1.2],
        l: [0.8, 0.6],
    };
    let (th, w, tau) = ([0.4, 1.5], [1.0, -2.0], [12.0, -3.5]);
    let mech = mechanisms::double_pendulum(dp, th, w, tau);
    // Absolute-angle generalized forces of the joint torques: [τ₁ − τ₂, τ₂].
    let acc = dp.accelerations(th, w, [tau[0] - tau[1], tau[1]]);
    for be in BACKENDS {
        let (qdd, _) = solve(&mech, be);
        assert!(
            rel(qdd[2], acc[0], 10.0) < 1e-12 && rel(qdd[5], acc[1], 10.0) < 1e-12,
            "{be:?}"
        );
    }
}

#[test]
fn rod_and_disk_matches_closed_form() {
    // The disk is pinned at its centre: it spins freely (α_disk = 0) and acts on the rod as a point
    // mass at the tip: (m_r L²/3 + m_d L²) θ̈ = −g L (m_r/2 + m_d) cos θ.
    let (mr, l, md, r) = (1.5, 1.2, 4.0, 0.3);
    for &(th, w) in &[(0.2, 0.0), (-0.9, 3.0)] {
        let mech = mechanisms::rod_and_disk(mr, l, md, r, th, w, 5.0);
        let alpha = -G * l * (mr / 2.0 + md) * th.cos() / (mr * l * l / 3.0 + md * l * l);
        for be in BACKENDS {
            let (qdd, _) = solve(&mech, be);
            assert!(rel(qdd[2], alpha, G) < 1e-12, "{be:?} {} vs {alpha}", qdd[2]);
            assert!(qdd[5].abs() < 1e-12 * G, "disk α {}", qdd[5]);
            // Disk centre = rod tip: a = L(−sθ α − cθ ω², cθ α − sθ ω²).
            let (s, c) = th.sin_cos();
            assert!(rel(qdd[3], l * (-s * alpha - c * w * w), G) < 1e-12);
            assert!(rel(qdd[4], l * (c * alpha - s * w * w), G) < 1e-12);
        }
    }
}

#[test]
fn four_bar_with_crank_torque_matches_minimal_coordinate_derivation() {
    let fb = FourBar::ANCHOR;
    for &(phi, phi_dot, tau) in &[(std::f64::consts::PI, 0.0, 0.0), (2.5, 1.5, 20.0), (4.0, -2.0, -5.0)] {
        let mech = mechanisms::four_bar(phi, phi_dot, tau, false);
        let alpha = fb.crank_acceleration(phi, phi_dot, tau);
        let expected = fb.accelerations(phi, phi_dot, alpha);
        for be in BACKENDS {
            let (qdd, _) = solve(&mech, be);
            for i in 0..9 {
                assert!(
                    rel(qdd[i], expected[i], 10.0) < 1e-12,
                    "{be:?} q̈[{i}] {} vs {}",
                    qdd[i],
                    expected[i]
                );
            }
        }
    }
}
