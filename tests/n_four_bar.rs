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
//! position decides the branch. A step that leaves the branch stops the run
//! (`IntegrationError::BranchSwitch`: its projection removed a large share of the kinetic energy,
//! or the energy of the conservative model jumped); pinned in `a_branch_switch_stops_the_run` and
//! `smaller_steps_keep_the_branch_or_stop`.

use dalembert::integrators::{IntegrationError, IntegratorOptions, Method, Stabilization, Statistics};
use dalembert::scene::Scene;
use dalembert::simulation::{FormulationKind, SimulationError};
use dalembert_testkit::n_four_bar::{NFourBar, Variant};

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
    b0_error_with(
        n,
        kind,
        IntegratorOptions::fixed(Method::rk4(), h, EVERY).with_stabilization(PROJECTION),
    )
}

/// [`b0_error_so_far`] with any integrator options: the model as written ([`NFourBar::toml`],
/// which is [`NFourBar::variant`]'s seed 0).
fn b0_error_with(n: usize, kind: FormulationKind, options: IntegratorOptions) -> (f64, Result<(), SimulationError>) {
    let (worst, result) = run_written(n, &NFourBar { n }.variant(END, 0), END, kind, options);
    (worst, result.map(|_| ()))
}

/// Largest `B₀` error of the model written as `v`, run to `end`, against the reduction from the
/// variant's start over the benchmark's output grid, and how the run ended (a run that ends well
/// must have given every output) with its statistics.
fn run_written(
    n: usize,
    v: &Variant,
    end: f64,
    kind: FormulationKind,
    options: IntegratorOptions,
) -> (f64, Result<Statistics, SimulationError>) {
    let reference = NFourBar { n }.reference_from(v.start, EVERY, end);
    let scene = Scene::from_toml(&v.toml, "n-four-bar").unwrap();
    let mut sim = scene.simulation();
    sim.formulation = kind;
    sim.integrator = options;
    let (mut worst, mut k) = (0.0f64, 0);
    let result = sim.run(&mut |s| {
        let (t, th, _) = reference[k];
        assert!((t - s.t).abs() < 1e-9, "output times {t} and {}", s.t);
        worst = worst.max(NFourBar::b0_error(&s.q[3 * v.first_crank..], th));
        k += 1;
    });
    if result.is_ok() {
        assert_eq!(k, reference.len(), "{}", v.description);
    }
    (worst, result)
}

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
fn one_window() {
    // Measured at h = 1 ms (2026-11-25): 1.0e-8 / 5.5e-9 / 5.5e-9 (augmented / embedding /
    // amalgamated). Asserted: 1e-6. (N = 2 and 4, as written and nine other ways:
    // `every_formulation_passes_every_way_of_writing_the_model`.)
    for kind in FormulationKind::ALL {
        let e = b0_error(1, kind, 1e-3).unwrap();
        assert!(e < 1e-6, "N = 1, {}: B0 error {e:e}", kind.name());
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
    // 1.7e-3). Measured again 2026-11-28, with the partition held through each step: 4.7e-6 /
    // 8.3e-5 / 9.1e-7, a draw of where the stages fall near the 800 loop passes; with the kicks of
    // the energy at the passes undone (`kicks_at_the_passes_are_undone`): 1.0e-8 / 2.0e-7 /
    // 1.6e-7 (docs/stability.md).
    for kind in FormulationKind::ALL {
        let e = b0_error(40, kind, 1e-3).unwrap();
        assert!(e < 1e-3, "{}: B0 error {e:e}", kind.name());
    }
}

/// Asserts the property the issue asks for at a setting that left the branch before the
/// branch-switch check: the run either keeps within `bar` to the end, or stops with
/// `BranchSwitch` having kept it up to there; ending off the branch silently fails.
fn keeps_the_branch_or_stops(n: usize, kind: FormulationKind, h: f64, bar: f64) {
    let (worst, result) = b0_error_so_far(n, kind, h);
    match result {
        Ok(()) => {}
        Err(SimulationError::Integration(f)) if matches!(f.error, IntegrationError::BranchSwitch { .. }) => {}
        Err(e) => panic!("N = {n}, {}, h = {h}: {e}", kind.name()),
    }
    assert!(
        worst < bar,
        "N = {n}, {}, h = {h}: B0 error {worst:e} before the end",
        kind.name()
    );
}

#[test]
fn a_branch_switch_stops_the_run() {
    // The settings that ended off the branch without a word before the check (measured
    // 2026-11-25 with `cargo run --release --example n_four_bar -- N 20 rk4`, the check off):
    // N = 40 augmented h = 0.5 ms ended 0.28 off (the projection removed 9.0e-3 of the kinetic
    // energy in one step; now stops at 18.41 s, 6.7e-6 off up to there); N = 2 h = 0.1 ms ended
    // 0.14 (augmented) and 2.7e-2 (embedding, amalgamated) off (the energy jumped by 5.0e-5 and
    // 4.1e-5 of the kinetic energy in one step; now stops at 4.60 s and 5.11 s, within 3.1e-5 and
    // 9.9e-7); N = 4 augmented h = 0.25 ms ended 7.8e-3 off and embedding h = 0.5 ms 1.8e-2 (now
    // stop at 3.19 s and 8.53 s, within 1.1e-6); N = 40 embedding h = 0.5 ms ended 1.9e-2 off (now
    // stops at 11.07 s, 1.9e-4 off up to there: in the 6 s of the test budget it is left to the
    // example). Runs that kept the branch do not stop (N = 1, 2,
    // 4 and 40 at h = 2, 1 ms, and those in `smaller_steps_keep_the_branch_or_stop`).
    // (N = 2 at 0.1 ms: `smaller_steps_keep_the_branch_or_stop`.)
    // Measured 2026-11-28 with the kicks of the energy undone (`kicks_at_the_passes_are_undone`):
    // N = 40 augmented 0.5 ms 2.1e-10 to the end; N = 4 embedding 0.5 ms 1.1e-9; N = 4 augmented
    // 0.25 ms still stops at 3.19 s on the projection's sign (1.4e-3 of the kinetic energy), with
    // 1.9e-11 up to there, and with that stop switched off (a throwaway build) it goes on along
    // its branch to 8.1e-7 at the end: none of these, checked with the checks off, had left its
    // branch; their errors were the phase of a kicked energy (docs/stability.md).
    keeps_the_branch_or_stops(40, FormulationKind::Augmented, 5e-4, 1e-3);
    keeps_the_branch_or_stops(4, FormulationKind::Augmented, 2.5e-4, 1e-3);
    keeps_the_branch_or_stops(4, FormulationKind::Embedding, 5e-4, 1e-3);
}

#[test]
fn generalized_alpha_stops_at_a_pass_with_the_cause() {
    // Generalized-α (ρ∞ = 0.8, h = 1 ms) on N = 40: its Newton matrix [M C_qᵀ; C_q 0] loses 40
    // ranks at the first pass and halving the step only lands nearer (measured 2026-11-25: stops
    // at t = 1.244 s, B₀ within 2.9e-5 up to there; the message used to be a bare "step size below
    // the minimum, error estimate NaN"). Asserted: on the branch to the benchmark's 1e-3 up to the
    // end or up to a stop that names the singular position and its equations.
    let (worst, result) = b0_error_with(
        40,
        FormulationKind::Augmented,
        IntegratorOptions::fixed(Method::generalized_alpha(0.8), 1e-3, EVERY),
    );
    match result {
        Ok(()) => {}
        Err(SimulationError::Integration(f)) => match &f.error {
            IntegrationError::SingularPass { involved, .. } => assert!(involved.len() >= 40, "{}", f.error),
            e => panic!("{e}"),
        },
        Err(e) => panic!("{e}"),
    }
    assert!(worst < 1e-3, "B0 error {worst:e} before the end");
}

#[test]
fn smaller_steps_keep_the_branch_or_stop() {
    // N = 2 at steps below the documented 1 ms. There a stage lands nearer a singular position,
    // where the rounding left in the state is amplified into a kick of the energy
    // (docs/stability.md). Before the kicks were undone (2026-11-28, `cargo run --release
    // --example n_four_bar -- 2 20 rk4`) at h = 0.5 / 0.25 / 0.1 ms: augmented 1.7e-9 / 2.4e-8 /
    // stops at 4.60 s (`BranchSwitch`; with the check off its cranks stay parallel to 1e-12 and
    // it ends 5.4e-2 off in phase: a kick, not a switch); embedding 7.9e-9 / 4.8e-8 / stops at
    // 12.37 s; amalgamated 6.4e-8 / 4.6e-4 / 5.0e-7. With the kicks undone: augmented 8.2e-11 /
    // 1.5e-10 / 1.1e-7; embedding 1.2e-10 / 2.9e-10 / 1.2e-10; amalgamated 1.6e-10 / 1.8e-9 /
    // 1.9e-10. Written ten ways at 0.1 ms, some still stop at the projection's sign (a kick the
    // projection removed, t = 6.54 s), within 1.1e-7 up to there. Asserted: the 1e-6 to
    // the end, or up to a stop that names the branch switch; never a silent departure.
    for kind in FormulationKind::ALL {
        for h in [5e-4, 2.5e-4, 1e-4] {
            keeps_the_branch_or_stops(2, kind, h, 1e-6);
        }
    }
}

/// Largest `B₀` error of one way of writing the model ([`NFourBar::variant`]) against the
/// reduction from the variant's start, and how the run ended.
fn variant_error(n: usize, seed: u64, kind: FormulationKind, options: IntegratorOptions) -> (f64, Result<(), String>) {
    let end = if seed.is_multiple_of(2) { 20.0 } else { 21.0 };
    let v = NFourBar { n }.variant(end, seed);
    let (worst, result) = run_written(n, &v, end, kind, options);
    let result = result
        .map(|_| ())
        .map_err(|e| format!("N = {n}, {}, {}: {e}", kind.name(), v.description));
    (worst, result)
}

#[test]
fn every_formulation_passes_every_way_of_writing_the_model() {
    // The setting docs/stability.md names for every formulation (RK4 + projection, h = 1 ms) on
    // A02 written ten ways with N = 2 and with N = 4 (`NFourBar::variant`: bodies and joints
    // shuffled, joints by global or local points, odd seeds from a start moved by up to 1e-12 and
    // run to 21 s, seeds 3 and 7 with every body moved by its own 1e-12 as well), against the
    // reduction from each variant's start. Measured 2026-11-28
    // (`cargo run --release --example n_four_bar_variants -- N 10 1e-3 each`): N = 2 worst 1.5e-8
    // / 1.4e-8 / 3.4e-8 (augmented / embedding / amalgamated); N = 4 worst 5.5e-7 / 5.0e-8 /
    // 1.1e-6, and 1.3e-8 / 5.0e-8 / 5.6e-8 with the kicks at the passes undone (before the
    // variants kept the link lengths, the moved ones gave 1.5e-4 … 5.3e-4: see
    // `NFourBar::with_lengths_moved`). Asserted: the 1e-6 for N = 2 and the benchmark's 1e-3 for N = 4, on every
    // variant, with no stop.
    let options = IntegratorOptions::fixed(Method::rk4(), 1e-3, EVERY).with_stabilization(PROJECTION);
    for (n, bar) in [(2, 1e-6), (4, 1e-3)] {
        for kind in FormulationKind::ALL {
            for seed in 0..10u64 {
                let (worst, result) = variant_error(n, seed, kind, options);
                result.unwrap_or_else(|e| panic!("{e}"));
                assert!(worst < bar, "N = {n}, {}, seed {seed}: B0 error {worst:e}", kind.name());
            }
        }
    }
}

#[test]
fn forty_windows_written_other_ways() {
    // A02 as specified (N = 40) written another way (seed 1: bodies and joints shuffled, the start
    // moved by up to 1e-12, 21 s; the as-written model is `forty_windows_within_the_benchmark_…`),
    // RK4 + projection at h = 1 ms with every formulation. Measured 2026-11-28 on all ten
    // (`cargo run --release --example n_four_bar_variants -- 40 10 1e-3 each`, the partition held
    // through each step): worst 3.9e-5 / 1.6e-4 / 5.0e-4 (augmented / embedding / amalgamated),
    // and the amalgamated run of seed 9 stopped at 18.41 s with `BranchSwitch` on a kept branch
    // (a kick of the energy of 1.0e-5 of the largest kinetic energy at a pass). With the kicks
    // undone (`kicks_at_the_passes_are_undone`): worst 1.3e-8 / 2.5e-7 / 2.1e-7, no stop. Asserted:
    // the benchmark's 1e-3, no stop, on seed 1 with every formulation and on the run that stopped.
    let options = IntegratorOptions::fixed(Method::rk4(), 1e-3, EVERY).with_stabilization(PROJECTION);
    let runs = FormulationKind::ALL.map(|kind| (1, kind));
    for (seed, kind) in runs.into_iter().chain([(9, FormulationKind::Amalgamated)]) {
        let (worst, result) = variant_error(40, seed, kind, options);
        result.unwrap_or_else(|e| panic!("{e}"));
        assert!(worst < 1e-3, "N = 40, {}, seed {seed}: B0 error {worst:e}", kind.name());
    }
}

#[test]
fn ali3p_passes_every_way_of_writing_the_model() {
    // ALI3-P (h = 1 ms, the automatic penalty) on the ten ways of writing A02 N = 2 of
    // `every_formulation_passes_every_way_of_writing_the_model`. Measured 2026-11-28
    // (`cargo run --release --example n_four_bar_variants -- 2`): 4.6e-4 on every 20 s variant and
    // 5.2e-4 on every 21 s one, its second-order truncation error (RK4 + projection at the same
    // step: 1e-8). Asserted: every variant within the benchmark's 1e-3, and the error independent
    // of how the model is written: the variants of one end time agree to 1e-6 (measured spread
    // 3.9e-9 on 4.6e-4).
    let mut by_end: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for seed in 0..10u64 {
        let options = IntegratorOptions::fixed(Method::ali3p(0.0), 1e-3, EVERY);
        let (worst, result) = variant_error(2, seed, FormulationKind::Augmented, options);
        result.unwrap_or_else(|e| panic!("{e}"));
        assert!(worst < 1e-3, "seed {seed}: B0 error {worst:e}");
        by_end[(seed % 2) as usize].push(worst);
    }
    for errors in &by_end {
        let spread = errors.iter().fold(0.0f64, |m, e| m.max((e - errors[0]).abs()));
        assert!(spread < 1e-6, "errors {errors:?} depend on how the model is written");
    }
}

#[test]
fn kicks_at_the_passes_are_undone() {
    // A02 N = 2 at h = 0.25 ms (RK4 + projection), written three ways, every formulation. A stage
    // that lands near a pass amplifies the rounding left in the state into a jump of `T + V`;
    // the run gives a conservative model's energy back where one step changed it 100 times more
    // than the steps before near a singular position (`Statistics::kicks_undone`,
    // docs/stability.md "Kicks at singular positions"). Before (2026-11-28, same code without
    // the undo): the as-written amalgamated run ended 4.6e-4 off, the ten ways of writing it
    // scattered up to 1e-3. Measured with it (`cargo run --release --example n_four_bar_variants
    // -- 2 10 1e-3 each 2.5e-4`): worst over ten ways 8.8e-8 / 2.6e-7 / 5.0e-9 (augmented /
    // embedding / amalgamated). Asserted: no stop, the 1e-6 against the reduction, the
    // energy (a first integral here) within 1e-9 of its scale, and the undo exercised.
    // This step is below the documented 1 ms, where the place the stages fall still decides some
    // runs: taking the energy after an undo from the scaled product instead of evaluating it
    // again (a change of the last bit) made the amalgamated run of seed 1 stop at 12.88 s on
    // the projection's sign. A change of rounding that moves this test is to be read that way
    // (docs/stability.md, "Kicks at singular positions"). At the documented 1 ms on N = 4, the
    // same three ways undo 0 … 3 kicks per run and end within 1.0e-8, energy within 3.2e-9 J.
    let options = IntegratorOptions::fixed(Method::rk4(), 2.5e-4, EVERY).with_stabilization(PROJECTION);
    let mut undone = 0;
    for kind in FormulationKind::ALL {
        for seed in 0..3u64 {
            let end = if seed.is_multiple_of(2) { 20.0 } else { 21.0 };
            let v = NFourBar { n: 2 }.variant(end, seed);
            let (worst, result) = run_written(2, &v, end, kind, options);
            let s = result.unwrap_or_else(|e| panic!("{}, {}: {e}", kind.name(), v.description));
            eprintln!(
                "{} seed {seed}: B0 {worst:.1e}, energy {:.1e} of {:.1e}, {} kicks undone",
                kind.name(),
                s.max_energy_change,
                s.energy_scale,
                s.kicks_undone
            );
            assert!(worst < 1e-6, "{}, seed {seed}: B0 error {worst:e}", kind.name());
            assert!(
                s.max_energy_change < 1e-9 * s.energy_scale,
                "{}, seed {seed}: energy change {:e} of scale {:e}",
                kind.name(),
                s.max_energy_change,
                s.energy_scale
            );
            undone += s.kicks_undone;
        }
    }
    assert!(undone > 0, "no kick undone: the case no longer exercises the undo");
}

#[test]
fn a_departure_from_the_reduction_still_stops() {
    // A02 N = 40 with its link lengths moved by up to 1e-12 (`NFourBar::with_lengths_moved`):
    // another mechanism, whose exact motion cannot follow the reduction through the flat
    // positions. At h = 1 ms (RK4 + projection, augmented) the run leaves it at t = 8.585 s, where
    // the projection removes 0.13 of the largest kinetic energy (measured 2026-11-28, with the
    // kicks of the energy undone; every one of ten such models stops there; before the undo they
    // stopped at the first flat position, 1.24 s, on the energy's sign). Asserted: the run stops
    // with `BranchSwitch` after the start, on the reduction to the benchmark's 1e-3 up to it
    // (measured 4.9e-7): the undo does not carry a run past a departure.
    let bar = NFourBar { n: 40 };
    let v = bar.with_lengths_moved(END, 0);
    let options = IntegratorOptions::fixed(Method::rk4(), 1e-3, EVERY).with_stabilization(PROJECTION);
    let (worst, result) = run_written(40, &v, END, FormulationKind::Augmented, options);
    match result {
        Err(SimulationError::Integration(f)) => match &f.error {
            IntegrationError::BranchSwitch { time, .. } => assert!(*time > 1.0, "stopped at {time}"),
            e => panic!("{e}"),
        },
        other => panic!("expected a BranchSwitch stop: {:?}", other.map(|_| ())),
    }
    assert!(worst < 1e-3, "B0 error {worst:e} before the stop");
}
