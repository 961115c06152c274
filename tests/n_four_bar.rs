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
//! `cargo run --release --example n_four_bar -- 40`, a step landing closer to the singular
//! position can leave the branch silently (N = 40: augmented h = 2 ms 0.42; embedding h = 0.5 ms
//! 1.4); at N = 2 the augmented formulation ends 4.3e-6 off at h = 2.5e-4.
//! `smaller_steps_keep_the_branch` states that target and is ignored until it holds.

use dalembert::integrators::{IntegratorOptions, Method, Stabilization};
use dalembert::scene::Scene;
use dalembert::simulation::{FormulationKind, SimulationError};
use dalembert_testkit::n_four_bar::NFourBar;

const END: f64 = 20.0;
const EVERY: f64 = END / 400.0;
const PROJECTION: Stabilization = Stabilization::Projection { tolerance: 1e-12 };

/// Largest `B₀` error against the reduction over the benchmark's output grid.
fn b0_error(n: usize, kind: FormulationKind, h: f64) -> Result<f64, SimulationError> {
    let bar = NFourBar { n };
    let reference = bar.reference(EVERY, END);
    let scene = Scene::from_toml(&bar.toml(END), "n-four-bar").unwrap();
    let mut sim = scene.simulation();
    sim.formulation = kind;
    sim.integrator = IntegratorOptions::fixed(Method::rk4(), h, EVERY).with_stabilization(PROJECTION);
    let (mut worst, mut k) = (0.0f64, 0);
    sim.run(&mut |s| {
        let (t, th, _) = reference[k];
        assert!((t - s.t).abs() < 1e-9, "output times {t} and {}", s.t);
        worst = worst.max(NFourBar::b0_error(s.q, th));
        k += 1;
    })?;
    assert_eq!(k, reference.len());
    Ok(worst)
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
    // amalgamated 2.0e-9 (1.6e-8 before the hand-over to the mass-orthogonal projection).
    for kind in KINDS {
        let e = b0_error(2, kind, 1e-3).unwrap();
        assert!(e < 1e-6, "{}: B0 error {e:e}", kind.name());
    }
}

#[test]
fn one_and_four_windows() {
    // Measured at h = 1 ms (2026-11-25): N = 1: 1.0e-8 / 4.4e-9 / 4.4e-9; N = 4: 1.9e-7 / 1.1e-8 /
    // 1.1e-8 (augmented / embedding / amalgamated; with coordinate partitioning alone, before the
    // hand-over, the embedding and amalgamated gave 2.2e-8 and 3.3e-8). Asserted: 1e-6 for N = 1,
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
    // `cargo run --release --example n_four_bar -- 40 20 'h = 1e-3'`): augmented 2.9e-5 in 2.9 s;
    // embedding and amalgamated 1.1e-7 in 4–6 s, since their projection hands over to the
    // mass-orthogonal one at the passes (`dalembert_system::partition::MassOrthogonalProjection`;
    // coordinate partitioning alone gave 1.7e-3).
    for kind in KINDS {
        let e = b0_error(40, kind, 1e-3).unwrap();
        assert!(e < 1e-3, "{}: B0 error {e:e}", kind.name());
    }
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
