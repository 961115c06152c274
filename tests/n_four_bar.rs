//! The IFToMM A02 N-four-bar (issue 12) against its exact one-degree-of-freedom reduction
//! (`dalembert_testkit::n_four_bar`: `k θ̈ = −g c cos θ`, derived there by Lagrange's equations).
//! Every window passes a singular position (all links on the x axis, `C_q` loses `N` ranks) twice
//! per crank turn: 20 passes in 20 s (21 for N = 1).
//!
//! The error measure is the benchmark's: the largest deviation of the point `B₀` (tip of the first
//! crank) over 400 output steps of 20 s. Its targets: 1e-3 for N = 40, and the 1e-6 for
//! N = 2.
//!
//! What is pinned is what holds today, with the setting docs/stability.md recommends (RK4 with
//! projection at h = 1 ms). It is **not** robust to the step: measured with
//! `cargo run --release --example n_four_bar -- 40`, where the steps fall near the singular
//! position decides the branch. A switch the step's projection makes (it removes a large share of
//! the kinetic energy at once) stops the run (`IntegrationError::BranchSwitch`; pinned in
//! `a_branch_switch_stops_the_run`); a switch the integrator makes on its own is still silent at
//! N = 2 (RK4 at h = 1e-4: 0.14 augmented, 2.7e-2 embedding and amalgamated).
//! `smaller_steps_keep_the_branch` states that target and is ignored until it holds.

use dalembert::integrators::{IntegrationError, IntegratorOptions, Method, Stabilization};
use dalembert::scene::Scene;
use dalembert::simulation::{FormulationKind, SimulationError};
use dalembert_testkit::n_four_bar::NFourBar;

const END: f64 = 20.0;
const EVERY: f64 = END / 400.0;
const PROJECTION: Stabilization = Stabilization::Projection { tolerance: 1e-12 };

/// Largest `B₀` error against the reduction over the benchmark's output grid.
fn b0_error(n: usize, kind: FormulationKind, h: f64) -> Result<f64, SimulationError> {
    let (worst, result) = b0_error_so_far(n, kind, h);
    result.map(|()| worst)
}

/// Largest `B₀` error over the samples observed, and how the run ended.
fn b0_error_so_far(n: usize, kind: FormulationKind, h: f64) -> (f64, Result<(), SimulationError>) {
    let bar = NFourBar { n };
    let reference = bar.reference(EVERY, END);
    let scene = Scene::from_toml(&bar.toml(END), "n-four-bar").unwrap();
    let mut sim = scene.simulation();
    sim.formulation = kind;
    sim.integrator = IntegratorOptions::fixed(Method::rk4(), h, EVERY).with_stabilization(PROJECTION);
    let (mut worst, mut k) = (0.0f64, 0);
    let result = sim.run(&mut |s| {
        let (t, th, _) = reference[k];
        assert!((t - s.t).abs() < 1e-9, "output times {t} and {}", s.t);
        worst = worst.max(NFourBar::b0_error(s.q, th));
        k += 1;
    });
    if result.is_ok() {
        assert_eq!(k, reference.len());
    }
    (worst, result.map(|_| ()))
}

const KINDS: [FormulationKind; 3] = [
    FormulationKind::Augmented,
    FormulationKind::Embedding,
    FormulationKind::Amalgamated,
];

#[test]
fn the_scene_starts_on_the_reduction() {
    // Assembled start: cranks vertical, B₀ at (0, 1) moving at ẋ = 1 m/s exactly (the given crank
    // rate is held, not merely weighted), every crank at the same rate, couplers translating.
    let bar = NFourBar { n: 3 };
    let scene = Scene::from_toml(&bar.toml(1.0), "n-four-bar").unwrap();
    let sim = scene.simulation();
    let (x, y) = NFourBar::b0(&sim.q);
    assert!(x.abs() < 1e-15 && (y - 1.0).abs() < 1e-15, "B0 = ({x}, {y})");
    for i in 0..=3 {
        assert!(
            (sim.qd[3 * i + 2] + 1.0).abs() < 1e-14,
            "crank {i} rate {}",
            sim.qd[3 * i + 2]
        );
        // Crank centre at half the tip speed: ẋ = +0.5 m/s.
        assert!((sim.qd[3 * i] - 0.5).abs() < 1e-14 && sim.qd[3 * i + 1].abs() < 1e-14);
    }
    for i in 0..3 {
        let c = 3 * (4 + i);
        assert!((sim.qd[c] - 1.0).abs() < 1e-14 && sim.qd[c + 1].abs() < 1e-14 && sim.qd[c + 2].abs() < 1e-14);
    }
}

#[test]
fn reference_conserves_the_reduced_energy() {
    // The reduction's own check: ½ k θ̇² + g c sin θ is its first integral.
    let bar = NFourBar { n: 40 };
    let (k, c) = bar.reduced();
    let energy = |th: f64, w: f64| 0.5 * k * w * w + dalembert_testkit::mechanisms::G * c * th.sin();
    let r = bar.reference(EVERY, END);
    let e0 = energy(r[0].1, r[0].2);
    let worst = r
        .iter()
        .map(|&(_, th, w)| (energy(th, w) - e0).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-10 * e0.abs(), "reduced energy drifts by {worst:e}");
}

#[test]
fn two_windows_within_the_target_with_every_formulation() {
    // Target 1e-6 (issue 12). Measured at h = 1 ms (2026-11-25): augmented 1.1e-8, embedding and
    // amalgamated 3.5e-9 (1.6e-8 before the hand-over to the mass-orthogonal projection).
    for kind in KINDS {
        let e = b0_error(2, kind, 1e-3).unwrap();
        assert!(e < 1e-6, "{}: B0 error {e:e}", kind.name());
    }
}

#[test]
fn one_and_four_windows() {
    // Measured at h = 1 ms (2026-11-25): N = 1: 1.0e-8 / 5.5e-9 / 5.5e-9; N = 4: 9.0e-9 / 1.5e-8 /
    // 1.5e-8 (augmented / embedding / amalgamated; with coordinate partitioning alone, before the
    // hand-over, the embedding and amalgamated gave 2.2e-8 and 3.3e-8; the augmented 1.9e-7 before
    // its Schur complement fell back to LU when ill-conditioned). Asserted: 1e-6 for N = 1,
    // and the benchmark's 1e-3 for N = 4.
    for kind in KINDS {
        let e = b0_error(1, kind, 1e-3).unwrap();
        assert!(e < 1e-6, "N = 1, {}: B0 error {e:e}", kind.name());
        let e = b0_error(4, kind, 1e-3).unwrap();
        assert!(e < 1e-3, "N = 4, {}: B0 error {e:e}", kind.name());
    }
}

#[test]
fn forty_windows_within_the_benchmark_with_every_formulation() {
    // A02 as specified (N = 40, 20 s, high precision 1e-3). Measured (2026-11-25, release,
    // `cargo run --release --example n_four_bar -- 40 20 'h = 1e-3'`): augmented 4.7e-6 in 2.9 s
    // (2.9e-5 before its Schur complement fell back to LU when ill-conditioned:
    // `dalembert_system::linalg::SCHUR_FALLBACK_CONDITION`); embedding and amalgamated 5.6e-7 in
    // 4 s, since their projection hands over to the mass-orthogonal one at the passes
    // (`dalembert_system::partition::MassOrthogonalProjection`; coordinate partitioning alone gave
    // 1.7e-3).
    for kind in KINDS {
        let e = b0_error(40, kind, 1e-3).unwrap();
        assert!(e < 1e-3, "{}: B0 error {e:e}", kind.name());
    }
}

#[test]
fn a_branch_switch_stops_the_run() {
    // The one setting of the N = 40 grid (h = 2, 1, 0.5, 0.25, 0.1 ms × three formulations) whose
    // projection moved the motion to another branch (measured 2026-11-25 with
    // `cargo run --release --example n_four_bar -- 40 20 rk4`): augmented at h = 0.5 ms, where
    // before the stop the run ended 0.28 off. It now stops at t = 18.41 s, the step's projection
    // having removed 9.0e-3 of the largest kinetic energy (the other runs at most 8.7e-6 in a
    // step). What is asserted is the property, not the time: the run either keeps the benchmark's
    // 1e-3 to the end, or stops with the branch switch having kept it up to there; ending off the
    // branch silently fails.
    let (worst, result) = b0_error_so_far(40, FormulationKind::Augmented, 5e-4);
    match result {
        Ok(()) => {}
        Err(SimulationError::Integration(f)) if matches!(f.error, IntegrationError::BranchSwitch { .. }) => {}
        Err(e) => panic!("{e}"),
    }
    assert!(worst < 1e-3, "B0 error {worst:e} before the end");
}

#[test]
#[ignore = "open in issue 12: smaller steps land nearer the singular position and leave the branch silently"]
fn smaller_steps_keep_the_branch() {
    for kind in KINDS {
        for h in [5e-4, 2.5e-4, 1e-4] {
            match b0_error(2, kind, h) {
                Ok(e) => assert!(e < 1e-6, "{} h = {h}: B0 error {e:e}", kind.name()),
                // Stopping with the cause is acceptable; a silent branch switch is not.
                Err(e) => assert!(e.to_string().contains("singular position"), "{e}"),
            }
        }
    }
}
