//! The stepping loop allocates nothing after setup: a counting global allocator shows that running
//! twice as many steps costs no more allocations (setup is the same; any per-step allocation would
//! add hundreds). The shorter run, made first, may count one or two more for lazily initialized
//! library state; the test therefore requires `long ≤ short`. Every formulation × integrator:
//! augmented with its dense (four-bar) and sparse (chain of 64) back ends, embedding and
//! amalgamated (dense on the four-bar, sparse amalgamated system on the chain of 64); and the same
//! for spatial models (the anchors' slider-crank, a closed loop, and the spatial chain of 64), whose
//! steps also advance Euler parameters and normalize them; and the spatial chain in joint
//! coordinates (articulated-body algorithm, and the dense solve of the composite-rigid-body `M`).
//!
//! Only the test's own thread is counted: libtest's harness thread allocates when it prints "has
//! been running for over 60 seconds", which once fell inside a measured run on a loaded CI machine
//! (3440 allocations for 0.5 s, 3442 for 1 s: the two of that message).

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::{Augmented, AugmentedOptions, Backend};
use dalembert::embedding::{Embedding, EmbeddingOptions};
use dalembert::integrators::{integrate, Applies, IntegratorOptions, Method, Stabilization, METHODS};
use dalembert::system::Formulation;
use dalembert::system::{MultibodySystem, RedundancyTreatment};
use dalembert_testkit::mechanisms;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

struct Counting;

thread_local! {
    /// Set on the thread that runs the measured integrations.
    static COUNTED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

fn counted() -> bool {
    COUNTED.try_with(|c| c.get()).unwrap_or(false)
}

thread_local! {
    /// The allocations of this thread while it is counted: a counter per thread, so that a
    /// finished test's thread (still marked, sending its result to the harness after its lock is
    /// released) cannot add to the next test's measurement. With one counter for all threads,
    /// that send fell inside a measured loop on a loaded machine now and then ("0 allocations for
    /// 50 iterations, 1 for 100", a different case each time).
    static ALLOCATIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// This thread's allocations counted so far.
fn allocations_so_far() -> usize {
    ALLOCATIONS.with(|a| a.get())
}

fn count_one() {
    let _ = ALLOCATIONS.try_with(|a| a.set(a.get() + 1));
}

/// The counter is shared: the tests of this file run one at a time.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
static LIVE_BYTES: AtomicUsize = AtomicUsize::new(0);
static PEAK_BYTES: AtomicUsize = AtomicUsize::new(0);

fn grow(bytes: usize) {
    let now = LIVE_BYTES.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK_BYTES.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if counted() {
            count_one();
        }
        grow(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE_BYTES.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if counted() {
            count_one();
        }
        LIVE_BYTES.fetch_sub(layout.size(), Ordering::Relaxed);
        grow(new_size);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The formulations under test: `"augmented"` with `backend`, `"embedding"`, `"amalgamated"`.
/// A system and a consistent state.
struct Case {
    sys: Arc<dyn MultibodySystem>,
    q: Vec<f64>,
    qd: Vec<f64>,
}

fn formulation(kind: &str, case: &Case, backend: Backend) -> Box<dyn Formulation> {
    match kind {
        "embedding" => Box::new(Embedding::with_defaults(case.sys.clone())),
        "amalgamated" => Box::new(Amalgamated::with_defaults(case.sys.clone())),
        _ => Box::new(
            Augmented::new(
                case.sys.clone(),
                AugmentedOptions {
                    backend,
                    ..Default::default()
                },
            )
            .unwrap(),
        ),
    }
}

fn allocations(case: &Case, kind: &str, backend: Backend, opts: &IntegratorOptions, t_end: f64) -> usize {
    let mut f = formulation(kind, case, backend);
    let before = allocations_so_far();
    integrate(f.as_mut(), 0.0, t_end, &case.q, &case.qd, opts, &mut |_| {}).unwrap();
    allocations_so_far() - before
}

#[test]
fn stepping_allocates_nothing_after_setup() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let planar = |m: mechanisms::Mechanism| Case {
        sys: m.model,
        q: m.q,
        qd: m.qd,
    };
    let spatial = |m: Arc<dalembert::spatial::Model>| {
        let (q, qd) = m.initial_state();
        Case { sys: m, q, qd }
    };
    let four_bar = planar(mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false));
    let chain = planar(mechanisms::chain(1.0, 1.0, &[-0.3; 64], &[0.0; 64], &[]));
    let slider_crank_3d = spatial(dalembert_testkit::spatial::slider_crank_3d());
    let chain_3d = spatial(dalembert_testkit::spatial::chain3d(64));
    let forced_3d = spatial(dalembert_testkit::spatial::forced_double_pendulum());
    // In joint coordinates: the articulated-body algorithm (augmented with its automatic back end,
    // embedding, amalgamated), and the dense solve of M (composite-rigid-body algorithm) with the
    // recursive Newton–Euler forces.
    let joints_3d = {
        let jc = dalembert_testkit::spatial::chain3d(16)
            .joint_coordinates()
            .expect("chain3d is a tree");
        let (q, qd) = jc.initial_state();
        Case {
            sys: jc.system(),
            q,
            qd,
        }
    };
    // Every registered integrator with its default parameters, and every stabilization for those
    // that do not keep the constraints themselves.
    let mut cases = Vec::new();
    for entry in METHODS {
        let names: &[&str] = if entry.keeps_constraints {
            &["none"]
        } else {
            Stabilization::NAMES
        };
        for name in names {
            let st = Stabilization::parse(name).unwrap();
            let opts = IntegratorOptions::fixed(Method::of(entry), 1e-3, 0.1).with_stabilization(st);
            cases.push((format!("{} + {name}", entry.name), opts));
        }
    }
    let mut failures = Vec::new();
    for (mech, kind, backend, what) in [
        (&four_bar, "augmented", Backend::Dense, "four-bar, augmented, dense"),
        (&chain, "augmented", Backend::Sparse, "chain of 64, augmented, sparse"),
        (&chain, "augmented", Backend::Tree, "chain of 64, augmented, tree"),
        (&four_bar, "embedding", Backend::Auto, "four-bar, embedding"),
        (
            &joints_3d,
            "augmented",
            Backend::Auto,
            "spatial chain of 16 in joint coordinates, augmented (articulated body)",
        ),
        (
            &joints_3d,
            "augmented",
            Backend::Dense,
            "spatial chain of 16 in joint coordinates, augmented, dense",
        ),
        (
            &joints_3d,
            "embedding",
            Backend::Auto,
            "spatial chain of 16 in joint coordinates, embedding",
        ),
        (
            &joints_3d,
            "amalgamated",
            Backend::Auto,
            "spatial chain of 16 in joint coordinates, amalgamated",
        ),
        (&chain, "embedding", Backend::Auto, "chain of 64, embedding"),
        (&four_bar, "amalgamated", Backend::Auto, "four-bar, amalgamated (dense)"),
        (
            &chain,
            "amalgamated",
            Backend::Auto,
            "chain of 64, amalgamated (sparse)",
        ),
        (
            &slider_crank_3d,
            "augmented",
            Backend::Auto,
            "spatial slider-crank, augmented",
        ),
        (
            &chain_3d,
            "augmented",
            Backend::Sparse,
            "spatial chain of 64, augmented, sparse",
        ),
        (
            &chain_3d,
            "augmented",
            Backend::Tree,
            "spatial chain of 64, augmented, tree",
        ),
        (
            &slider_crank_3d,
            "embedding",
            Backend::Auto,
            "spatial slider-crank, embedding",
        ),
        (&chain_3d, "embedding", Backend::Auto, "spatial chain of 64, embedding"),
        (
            &slider_crank_3d,
            "amalgamated",
            Backend::Auto,
            "spatial slider-crank, amalgamated",
        ),
        (
            &chain_3d,
            "amalgamated",
            Backend::Auto,
            "spatial chain of 64, amalgamated",
        ),
        (
            &forced_3d,
            "augmented",
            Backend::Auto,
            "spatial pendulum with every force element, augmented",
        ),
        (
            &forced_3d,
            "embedding",
            Backend::Auto,
            "spatial pendulum with every force element, embedding",
        ),
        (
            &forced_3d,
            "amalgamated",
            Backend::Auto,
            "spatial pendulum with every force element, amalgamated",
        ),
    ] {
        for (name, opts) in &cases {
            // Generalized-α integrates the augmented index-3 equations and refuses the others.
            if opts.method.entry().applies == Applies::AugmentedIndex3 && kind != "augmented" {
                continue;
            }
            // The chain's implicit steps are costly (finite-difference Jacobians): shorter runs.
            let long_model = std::ptr::eq(mech, &chain) || std::ptr::eq(mech, &chain_3d);
            let scale = if long_model { 0.1 } else { 1.0 };
            let short = allocations(mech, kind, backend, opts, 0.5 * scale);
            let long = allocations(mech, kind, backend, opts, scale);
            if long > short {
                failures.push(format!("{what}, {name}: {short} allocations for 0.5 s, {long} for 1 s"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");

    // Redundant constraints under the minimum-norm treatment (a parallelogram with a third crank:
    // rank 11 of 12), swinging about its lowest position, clear of the singular one at φ = 0: every
    // formulation finds the independent equations once and keeps them with the minimum-norm
    // multipliers' storage, so its steps allocate nothing either.
    let redundant = planar(mechanisms::parallelogram(-1.2, 0.5, true));
    let minimum_norm = RedundancyTreatment::MinimumNorm;
    for kind in ["augmented", "embedding", "amalgamated"] {
        for (name, opts) in &cases {
            if opts.method.entry().applies == Applies::AugmentedIndex3 && kind != "augmented" {
                continue;
            }
            let run = |t_end: f64| {
                let sys = redundant.sys.clone();
                let mut f: Box<dyn Formulation> = match kind {
                    "embedding" => Box::new(Embedding::new(
                        sys,
                        EmbeddingOptions {
                            redundancy: minimum_norm,
                            ..Default::default()
                        },
                    )),
                    "amalgamated" => Box::new(Amalgamated::new(sys, minimum_norm)),
                    _ => Box::new(
                        Augmented::new(
                            sys,
                            AugmentedOptions {
                                redundancy: minimum_norm,
                                ..Default::default()
                            },
                        )
                        .unwrap(),
                    ),
                };
                let before = allocations_so_far();
                integrate(f.as_mut(), 0.0, t_end, &redundant.q, &redundant.qd, opts, &mut |_| {})
                    .unwrap_or_else(|e| panic!("redundant parallelogram, {kind}, {name}: {e}"));
                allocations_so_far() - before
            };
            let (short, long) = (run(0.5), run(1.0));
            if long > short {
                failures.push(format!(
                    "redundant parallelogram, {kind}, {name}: {short} allocations for 0.5 s, {long} for 1 s"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");

    // Size: a chain of 10 000 bodies (30 000 coordinates, 20 000 equations). Setup and one RK4 step
    // with the augmented formulation (tree back end, sparse LU fallback set up) stay within 100 MB: memory linear in the
    // size (a dense matrix of that order would need 3.2 GB), and the step is timed.
    let n = 10_000;
    let angles: Vec<f64> = (0..n).map(|k| -0.3 - 1e-4 * k as f64).collect();
    let big = mechanisms::chain(1.0, 1.0, &angles, &vec![0.0; n], &[]);
    let base = LIVE_BYTES.load(Ordering::Relaxed);
    PEAK_BYTES.store(base, Ordering::Relaxed);
    let mut f = Augmented::with_defaults(big.model.clone()).unwrap();
    assert_eq!(f.backend_name(), "tree");
    let t0 = std::time::Instant::now();
    let mut finite = true;
    let stats = integrate(
        &mut f,
        0.0,
        1e-3,
        &big.q,
        &big.qd,
        &IntegratorOptions::fixed(Method::rk4(), 1e-3, 1e-3),
        &mut |s| {
            finite &= s.q.iter().all(|v| v.is_finite());
        },
    )
    .unwrap();
    let elapsed = t0.elapsed();
    let peak = PEAK_BYTES.load(Ordering::Relaxed) - base;
    assert!(finite && stats.steps == 1);
    assert!(peak < 100 << 20, "peak memory {} MB", peak >> 20);
    eprintln!(
        "chain of {n}: one RK4 step in {:.1} ms (loop {:.1} ms), peak {} MB",
        elapsed.as_secs_f64() * 1e3,
        stats.wall_time.as_secs_f64() * 1e3,
        peak >> 20
    );
}

/// The allocations of `iterations` rounds of the simulator's loop on `scene` after its
/// construction: the input (if any) set, an advance to a time between two steps, the reaction
/// column read, one step.
fn simulator_loop(scene: &dalembert::Scene, reaction: &str, input: Option<&str>, iterations: usize) -> usize {
    let mut sim = scene.simulator().unwrap();
    let before = allocations_so_far();
    for k in 1..=iterations {
        if let Some(name) = input {
            sim.set_input(name, (k as f64).sin()).unwrap();
        }
        sim.advance_to(sim.time().max(k as f64 * 3.7e-3)).unwrap();
        sim.value(reaction).unwrap();
        sim.step().unwrap();
    }
    allocations_so_far() - before
}

/// The simulator's loop (an input set, an advance to a time between two steps, a reaction read, a
/// step) allocates nothing after construction either: every formulation × method × stabilization,
/// on a planar slider-crank and a spatial one, each with a motor torque that is an input. Counted
/// as above: twice the iterations cost no more allocations.
#[test]
fn the_simulator_loop_allocates_nothing() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let with_motor = |path: &str, torque: &str| {
        let text = std::fs::read_to_string(path).unwrap();
        let text = format!("{text}\n[[forces]]\nname = \"commanded\"\ntype = \"torque\"\nbody = \"crank\"\n{torque}\n");
        dalembert::Scene::from_toml(&text, path).unwrap()
    };
    let scenes = [
        with_motor("scenes/slider-crank.toml", "value = { input = \"motor\" }"),
        with_motor("scenes/slider-crank-3d.toml", "tx = { input = \"motor\" }"),
    ];
    let mut failures = Vec::new();
    for base in &scenes {
        assert_eq!(base.inputs, ["motor"]);
        let reaction = base.check().unwrap().reactions[0].0.clone();
        for formulation in dalembert::FormulationKind::ALL {
            for entry in METHODS {
                if entry.applies == Applies::AugmentedIndex3 && formulation != dalembert::FormulationKind::Augmented {
                    continue;
                }
                let names: &[&str] = if entry.keeps_constraints {
                    &["none"]
                } else {
                    Stabilization::NAMES
                };
                for name in names {
                    let mut scene = base.clone();
                    scene.settings.formulation = formulation;
                    scene.settings.method = Method::of(entry);
                    scene.settings.stabilization = Stabilization::parse(name).unwrap();
                    scene.settings.step = 1e-3;
                    let count = |iterations| simulator_loop(&scene, &reaction, Some("motor"), iterations);
                    let (short, long) = (count(50), count(100));
                    if long > short {
                        failures.push(format!(
                            "{}, {}, {} + {name}: {short} allocations for 50 iterations, {long} for 100",
                            scene.origin,
                            formulation.name(),
                            entry.name
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The allocations of `counted` rounds of the simulator's loop (as [`simulator_loop`], without
/// inputs) on `scene` after `warm_up` rounds, and the re-partitions made while they were counted.
fn loop_after_warm_up(scene: &dalembert::Scene, warm_up: usize, counted: usize) -> (usize, u64) {
    let mut sim = scene.simulator().unwrap();
    let round = |sim: &mut dalembert::Simulator, k: usize| {
        sim.advance_to(sim.time().max(k as f64 * 3.7e-3)).unwrap();
        sim.step().unwrap();
    };
    for k in 1..=warm_up {
        round(&mut sim, k);
    }
    let (before, repartitions) = (allocations_so_far(), sim.statistics().repartitions);
    for k in warm_up + 1..=warm_up + counted {
        round(&mut sim, k);
    }
    (
        allocations_so_far() - before,
        sim.statistics().repartitions - repartitions,
    )
}

/// A re-partition allocates nothing where `C_qd` is factored dense: the choice's matrices, a spare
/// partition and velocity transformation, and the log's entries are set up with the first
/// partition. The double pendulum released horizontal and the UR5 swinging under gravity, in
/// absolute coordinates, with the embedding and amalgamated formulations and every method: after
/// 50 rounds, 300 more allocate nothing, while the partition changes in them (in one method at
/// least: the test would pass vacuously otherwise). Before, each re-partition made about 40
/// allocations. And a run of an adaptive method whose
/// steps shrink (dopri5 on the slider-crank whose motor input jumps every round) checks its
/// positions for a singular one without allocating (before: 5 allocations per check, of the SVD
/// of `C_q`).
#[test]
fn re_partitions_and_singularity_checks_allocate_nothing() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let mut failures = Vec::new();
    for path in ["scenes/double-pendulum.toml", "scenes/robots/ur5-swing.toml"] {
        let base = dalembert::Scene::from_path(path).unwrap();
        for formulation in [
            dalembert::FormulationKind::Embedding,
            dalembert::FormulationKind::Amalgamated,
        ] {
            let mut changes = 0;
            for entry in METHODS {
                if entry.applies == Applies::AugmentedIndex3 {
                    continue;
                }
                let mut scene = base.clone();
                scene.settings.formulation = formulation;
                scene.settings.method = Method::of(entry);
                scene.settings.step = 1e-3;
                let (count, repartitions) = loop_after_warm_up(&scene, 50, 300);
                changes += repartitions;
                if count > 0 {
                    failures.push(format!(
                        "{path}, {}, {}: {count} allocations, {repartitions} re-partitions in 300 rounds",
                        formulation.name(),
                        entry.name
                    ));
                }
            }
            if changes == 0 {
                failures.push(format!("{path}, {}: no re-partition was counted", formulation.name()));
            }
        }
    }
    let text = std::fs::read_to_string("scenes/slider-crank.toml").unwrap();
    let text = format!("{text}\n[[forces]]\nname = \"commanded\"\ntype = \"torque\"\nbody = \"crank\"\nvalue = {{ input = \"motor\" }}\n");
    let mut scene = dalembert::Scene::from_toml(&text, "slider-crank with a motor input").unwrap();
    scene.settings.method = Method::of(METHODS.iter().find(|e| e.name == "dopri5").unwrap());
    for formulation in dalembert::FormulationKind::ALL {
        scene.settings.formulation = formulation;
        let mut sim = scene.simulator().unwrap();
        let mut count = 0;
        for k in 1..=600 {
            let before = allocations_so_far();
            sim.set_input("motor", 40.0 * (k as f64).sin()).unwrap();
            sim.advance_to(sim.time().max(k as f64 * 3.7e-3)).unwrap();
            sim.step().unwrap();
            if k > 50 {
                count += allocations_so_far() - before;
            }
        }
        if count > 0 {
            failures.push(format!(
                "slider-crank with jumping input, {}, dopri5: {count} allocations in 550 rounds",
                formulation.name()
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The same loop (without inputs: joint coordinates take no force elements) on a spatial chain in
/// joint coordinates, every formulation × method: the map to the model's coordinates and the
/// evaluation of its reactions there allocate nothing either.
#[test]
fn the_simulator_loop_in_joint_coordinates_allocates_nothing() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let text = dalembert_testkit::spatial::chain3d_toml(4, 1.0)
        .replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n");
    let base = dalembert::Scene::from_toml(&text, "chain3d-4 joint").unwrap();
    let reaction = base.check().unwrap().reactions[0].0.clone();
    let mut failures = Vec::new();
    for formulation in dalembert::FormulationKind::ALL {
        for entry in METHODS {
            if entry.applies == Applies::AugmentedIndex3 && formulation != dalembert::FormulationKind::Augmented {
                continue;
            }
            let mut scene = base.clone();
            scene.settings.formulation = formulation;
            scene.settings.method = Method::of(entry);
            scene.settings.step = 1e-3;
            let count = |iterations| simulator_loop(&scene, &reaction, None, iterations);
            let (short, long) = (count(50), count(100));
            if long > short {
                failures.push(format!(
                    "{}, {}: {short} allocations for 50 iterations, {long} for 100",
                    formulation.name(),
                    entry.name
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A run carrying sensitivities allocates nothing per step either: RK4 carries each parameter's
/// tangent through its stages with storage sized at its first step, every other method takes
/// the run's steps again on each parameter's two models, built at setup. Every
/// formulation × method on the shipped slider-crank with two parameters: a run twice as long
/// costs no more allocations.
#[test]
fn a_run_with_sensitivities_allocates_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let base = dalembert::Scene::from_path("scenes/slider-crank.toml").unwrap();
    let request = dalembert::SensitivityRequest::new(
        &["bodies.slider.mass", "bodies.crank.mass"],
        &["slider.x", "crank.omega"],
    );
    let mut failures = Vec::new();
    for formulation in dalembert::FormulationKind::ALL {
        for entry in METHODS {
            if entry.applies == Applies::AugmentedIndex3 && formulation != dalembert::FormulationKind::Augmented {
                continue;
            }
            let mut scene = base.clone();
            scene.settings.formulation = formulation;
            scene.settings.method = Method::of(entry);
            scene.settings.step = 1e-3;
            let count = |end: f64| {
                let mut scene = scene.clone();
                scene.settings.end = end;
                let setup = scene.sensitivity_setup(&request).unwrap();
                let before = allocations_so_far();
                scene
                    .run_sensitivities(setup, &mut |_, _| {}, &std::sync::atomic::AtomicBool::new(false))
                    .unwrap();
                allocations_so_far() - before
            };
            let (short, long) = (count(0.2), count(0.4));
            if long > short {
                failures.push(format!(
                    "{}, {}: {short} allocations for 0.2 s, {long} for 0.4 s",
                    formulation.name(),
                    entry.name
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The allocations of a run of `scene` to `end`, and the events it crossed.
fn run_counted(scene: &dalembert::Scene, end: f64) -> (usize, u64) {
    let mut sim = scene.simulation();
    sim.end = end;
    let before = allocations_so_far();
    let stats = sim.run(&mut |_| {}).unwrap();
    (allocations_so_far() - before, stats.events)
}

/// A run whose steps end at contact events (the bouncing ball: touchdowns and lift-offs located
/// on the chord or the dense output) allocates nothing per step either, every method: a run
/// through twice the bounces costs no more allocations.
#[test]
fn a_run_with_contact_events_allocates_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let base = dalembert::Scene::from_path("scenes/bouncing-ball.toml").unwrap();
    let mut failures = Vec::new();
    for entry in METHODS {
        let mut scene = base.clone();
        scene.settings.method = Method::of(entry);
        scene.settings.step = 1e-4;
        let ((short, events_short), (long, events_long)) = (run_counted(&scene, 1.0), run_counted(&scene, 2.0));
        assert!(events_long > events_short, "{}: no contact event", entry.name);
        if long > short {
            failures.push(format!("{}: {short} allocations for 1 s, {long} for 2 s", entry.name));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Runs through two capsules (spatial, as a pair and as a group with its broad phase), two
/// rounded segments (planar), a roller on a turning cam profile (the closest points of two
/// segments, of a point and a spline, found at every evaluation), a box on a sliding plate and a
/// rectangle on a sliding platform (its line, and its polygon) allocate nothing per step, every method: a rod bouncing on a
/// log without dissipation, the cam turning, and the blocks falling onto their plates, for twice
/// as long cost no more allocations.
#[test]
fn runs_with_capsule_and_cam_contacts_allocate_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let profile: Vec<String> = (0..=32)
        .map(|k| {
            let a = std::f64::consts::TAU * (k % 32) as f64 / 32.0;
            format!("[{:?}, {:?}]", 0.05 * a.sin(), 0.01 + 0.05 * a.cos())
        })
        .collect();
    let texts = [
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"rod\"\nmass = 2.0\ninertia = [0.0009, 0.0277, 0.0277]\nposition = [0.0, 0.0, 0.3]\n\
         [[forces]]\nname = \"touch\"\ntype = \"capsule-capsule\"\nbodies = [\"ground\", \"rod\"]\n\
         segments = [[[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]], [[-0.2, 0.0, 0.3], [0.2, 0.0, 0.3]]]\n\
         radii = [0.1, 0.03]\nstiffness = 1e6\n"
            .to_string(),
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"rod\"\nmass = 2.0\ninertia = [0.0009, 0.0277, 0.0277]\nposition = [0.0, 0.0, 0.3]\n\
         [[forces]]\nname = \"touch\"\ntype = \"capsule-group\"\nmembers = [\
         { body = \"ground\", at = [[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]], radius = 0.1 }, \
         { body = \"rod\", at = [[-0.2, 0.0, 0.3], [0.2, 0.0, 0.3]], radius = 0.03 }]\n\
         stiffness = 1e6\n"
            .to_string(),
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"rod\"\nmass = 2.0\ninertia = 0.03\nposition = [0.0, 0.3]\n\
         [[forces]]\nname = \"touch\"\ntype = \"segment-segment\"\nbodies = [\"ground\", \"rod\"]\n\
         segments = [[[0.0, 0.0], [0.0, 0.0]], [[-0.2, 0.3], [0.2, 0.3]]]\n\
         radii = [0.1, 0.03]\nstiffness = 1e6\n"
            .to_string(),
        format!(
            "[scene]\ngravity = [0.0, -9.81]\n\
             [[bodies]]\nname = \"cam\"\nmass = 1.0\ninertia = 0.05\nposition = [0.0, 0.0]\nangular_velocity = 20.0\n\
             [[bodies]]\nname = \"follower\"\nmass = 0.5\ninertia = 1e-4\nposition = [0.0, 0.08]\n\
             [[joints]]\nname = \"shaft\"\ntype = \"revolute\"\nbodies = [\"ground\", \"cam\"]\nat = [0.0, 0.0]\n\
             [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"follower\"]\nat = [0.0, 0.08]\naxis = [0.0, 1.0]\n\
             [[forces]]\nname = \"touch\"\ntype = \"circle-profile\"\nbody = \"follower\"\nradius = 0.02\nstiffness = 1e7\n\
             profile = {{ body = \"cam\", points = [{}] }}\n",
            profile.join(", ")
        ),
        // A box on a plate's plane and a rectangle on a platform's line, the plate and the
        // platform free (docs/contact.md, "A line or plane on a moving body").
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"plate\"\nmass = 3.0\ninertia = [0.03, 0.04, 0.06]\nposition = [0.0, 0.0, 0.0]\n\
         [[bodies]]\nname = \"box\"\nmass = 1.0\ninertia = [0.004, 0.005, 0.006]\nposition = [0.0, 0.0, 0.2]\nangular_velocity = [1.0, 2.0, 0.0]\n\
         [[joints]]\nname = \"slide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"plate\"]\nat = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\n\
         [[forces]]\nname = \"touch\"\ntype = \"box-plane\"\nbody = \"box\"\nsize = [0.2, 0.15, 0.1]\n\
         plane = { body = \"plate\", point = [0.0, 0.0, 0.05], normal = [0.0, 0.0, 1.0] }\nstiffness = 1e6\n\
         dissipation = 0.5\nfriction = 0.3\n"
            .to_string(),
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"platform\"\nmass = 2.0\nshape = { rectangle = [0.6, 0.1] }\nposition = [0.0, -0.05]\n\
         [[bodies]]\nname = \"block\"\nmass = 1.0\nshape = { rectangle = [0.2, 0.1] }\nposition = [0.0, 0.3]\nangular_velocity = 3.0\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"platform\"]\nat = [0.0, -0.05]\naxis = [0.0, 1.0]\n\
         [[forces]]\nname = \"touch\"\ntype = \"polygon-line\"\nbody = \"block\"\n\
         vertices = [[-0.1, 0.25], [0.1, 0.25], [0.1, 0.35], [-0.1, 0.35]]\n\
         line = { body = \"platform\", point = [0.0, 0.0], normal = [0.0, 1.0] }\nstiffness = 1e6\n\
         dissipation = 0.5\nfriction = 0.3\n"
            .to_string(),
        // The same rectangle on the platform as two polygons (docs/contact.md, "Polygons against
        // polygons").
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"platform\"\nmass = 2.0\nshape = { rectangle = [0.6, 0.1] }\nposition = [0.0, -0.05]\n\
         [[bodies]]\nname = \"block\"\nmass = 1.0\nshape = { rectangle = [0.2, 0.1] }\nposition = [0.0, 0.3]\nangular_velocity = 3.0\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"platform\"]\nat = [0.0, -0.05]\naxis = [0.0, 1.0]\n\
         [[forces]]\nname = \"touch\"\ntype = \"polygon-polygon\"\nbodies = [\"platform\", \"block\"]\n\
         polygons = [[[-0.3, -0.1], [0.3, -0.1], [0.3, 0.0], [-0.3, 0.0]], [[-0.1, 0.25], [0.1, 0.25], [0.1, 0.35], [-0.1, 0.35]]]\n\
         stiffness = 1e6\ndissipation = 0.5\nfriction = 0.3\n"
            .to_string(),
    ];
    let mut failures = Vec::new();
    for text in &texts {
        let base = dalembert::Scene::from_toml(text, "contacts").unwrap();
        for entry in METHODS {
            let mut scene = base.clone();
            scene.settings.method = Method::of(entry);
            scene.settings.step = 1e-4;
            let ((short, _), (long, _)) = (run_counted(&scene, 0.5), run_counted(&scene, 1.0));
            if long > short {
                failures.push(format!("{}: {short} allocations for 0.5 s, {long} for 1 s", entry.name));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A run with joint friction (a pendulum with pin friction: the stick–slip law solved at every
/// evaluation, its responses from the formulation's factorization, its swings reversing at
/// events) allocates nothing per step, every formulation × every method that takes friction, in
/// absolute and joint coordinates: a run through twice the reversals costs no more allocations.
#[test]
fn a_run_with_joint_friction_allocates_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let text = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = { rod = 1.0 }\nposition = [0.5, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0]\n\
        friction = { coefficient = 0.2, radius = 0.05 }\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // The spatial rod in joint coordinates too: its load the force the joint transmits, from
    // the tree's recursive Newton–Euler pass (`docs/friction.md`, "In joint coordinates").
    let joint = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08333333333333333, 0.08333333333333333]\n\
        position = [0.5, 0.0, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
        axis = [0.0, -1.0, 0.0]\nfriction = { coefficient = 0.2, radius = 0.05 }\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\ncoordinates = \"joint\"\n";
    let failures = switching_runs_growing(&[text, joint], "reversal");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Each scene of `texts` in every formulation × every method that takes any formulation, run for
/// 1.5 s and 3 s: the longer run must cross more events (`what`) and allocate no more. The
/// failures, one line each.
fn switching_runs_growing(texts: &[&str], what: &str) -> Vec<String> {
    let mut failures = Vec::new();
    for text in texts {
        let base = dalembert::Scene::from_toml(text, "switching").unwrap();
        for formulation in ["augmented", "embedding", "amalgamated"] {
            for entry in METHODS.iter().filter(|e| e.applies == Applies::AnyFormulation) {
                let mut scene = base.clone();
                scene.settings.method = Method::of(entry);
                scene.settings.formulation = dalembert::FormulationKind::parse(formulation).unwrap();
                let ((short, events_short), (long, events_long)) = (run_counted(&scene, 1.5), run_counted(&scene, 3.0));
                assert!(events_long > events_short, "{formulation}, {}: no {what}", entry.name);
                if long > short {
                    failures.push(format!(
                        "{formulation}, {}: {short} allocations for 1.5 s, {long} for 3 s",
                        entry.name
                    ));
                }
            }
        }
    }
    failures
}

/// A run with a joint limit (impacts located, the joint held on its stop and released, its
/// events; `docs/limits.md`) allocates nothing per step, every formulation × every method that
/// takes limits: a rod swinging against stops on both sides of its pin with e = 0.5, through
/// twice the impacts, costs no more allocations.
#[test]
fn a_run_with_joint_limits_allocates_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let text = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = { rod = 1.0 }\nposition = [0.5, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0]\n\
        limits = [-2.0, 0.0]\nrestitution = 0.5\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // The same rod as a spatial body (its limit's row written for spatial bodies).
    let spatial = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08, 0.08]\nposition = [0.5, 0.0, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
        axis = [0.0, -1.0, 0.0]\nlimits = [-2.0, 0.0]\nrestitution = 0.5\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // A ball bouncing on a rigid floor (a rigid contact's gap row), e = 0.8.
    let ball = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"ball\"\nmass = 1.0\ninertia = [0.004, 0.004, 0.004]\nposition = [0.0, 0.0, 0.4]\n\
        [[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\n\
        plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\nrigid = true\nrestitution = 0.8\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // A disk thrown spinning onto a rigid floor with friction (e = 1, μ = 0.3): a tangential
    // impulse at each bounce (the friction's row and response in the impact).
    let disk = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"disk\"\nmass = 1.0\nshape = { disk = 0.1 }\nposition = [0.0, 0.4]\nvelocity = [2.0, 0.0]\nangular_velocity = 40.0\n\
        [[forces]]\nname = \"floor\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = 0.1\n\
        line = { point = [0.0, 0.0], normal = [0.0, 1.0] }\nrigid = true\nrestitution = 1.0\nfriction = 0.3\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // The spatial rod in joint coordinates (the limit's row a unit on the joint's rate; each
    // sample mapped back with the stop's force added).
    let joint = spatial.replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n");
    // A block on a rigid floor (its four corners, μ = 0.4) pushed to and fro (20 N at 1 Hz):
    // stick and slip of two redundant corners (their least-norm forces and impulses).
    let pushed = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"block\"\nmass = 2.0\nshape = { rectangle = [0.4, 0.2] }\nposition = [0.0, 0.1]\n\
        [[forces]]\nname = \"floor\"\ntype = \"polygon-line\"\nbody = \"block\"\n\
        vertices = [[-0.2, 0.0], [0.2, 0.0], [0.2, 0.2], [-0.2, 0.2]]\n\
        line = { point = [0.0, 0.0], normal = [0.0, 1.0] }\nrigid = true\nfriction = 0.4\n\
        [[forces]]\nname = \"push\"\ntype = \"force\"\nbody = \"block\"\n\
        fx = { kind = \"harmonic\", amplitude = 20.0, frequency = 1.0 }\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // The same block dropped level at 3 m/s onto the floor with e = 1: both lower corners strike
    // together at every bounce (their impulses solved together, with their friction's, slipping
    // and then stuck).
    let landing = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"block\"\nmass = 2.0\nshape = { rectangle = [0.4, 0.2] }\nposition = [0.0, 0.2]\nvelocity = [3.0, 0.0]\n\
        [[forces]]\nname = \"floor\"\ntype = \"polygon-line\"\nbody = \"block\"\n\
        vertices = [[-0.2, 0.1], [0.2, 0.1], [0.2, 0.3], [-0.2, 0.3]]\n\
        line = { point = [0.0, 0.0], normal = [0.0, 1.0] }\nrigid = true\nfriction = 0.4\nrestitution = 1.0\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // A spinning ball bouncing on a rigid floor with friction (e = 1, μ = 0.3): a friction cone's
    // two-dimensional impulse at each bounce.
    let spinning = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"ball\"\nmass = 1.0\nshape = { sphere = 0.1 }\nposition = [0.0, 0.0, 0.4]\n\
        velocity = [1.0, 0.5, 0.0]\nangular_velocity = [10.0, -20.0, 5.0]\n\
        [[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\n\
        plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\nrigid = true\nrestitution = 1.0\nfriction = 0.3\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // A ball on a rigid floor with friction pushed to and fro at 1 Hz (20 N along x, 4 N along
    // y): its cone sticks and slips in a turning direction each cycle.
    let rolled = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"ball\"\nmass = 1.0\nshape = { sphere = 0.1 }\nposition = [0.0, 0.0, 0.1]\n\
        [[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\n\
        plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }\nrigid = true\nfriction = 0.3\n\
        [[forces]]\nname = \"push\"\ntype = \"force\"\nbody = \"ball\"\n\
        fx = { kind = \"harmonic\", amplitude = 20.0, frequency = 1.0 }\nfy = 4.0\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    // Two spinning balls tied by a spring, without gravity, striking each other obliquely again
    // and again (e = 1, μ = 0.3): a sphere–sphere friction cone's impulses, its tangent rows
    // turning with the line of centres.
    let pair = "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
        [[bodies]]\nname = \"a\"\nmass = 1.0\nshape = { sphere = 0.1 }\nposition = [0.0, 0.0, 0.0]\nangular_velocity = [0.0, 0.0, 10.0]\n\
        [[bodies]]\nname = \"b\"\nmass = 1.0\nshape = { sphere = 0.1 }\nposition = [0.3, 0.0, 0.0]\n\
        velocity = [-2.0, 0.3, 0.0]\nangular_velocity = [3.0, -2.0, 0.0]\n\
        [[forces]]\nname = \"touch\"\ntype = \"sphere-sphere\"\nbodies = [\"a\", \"b\"]\nradii = [0.1, 0.1]\n\
        rigid = true\nrestitution = 1.0\nfriction = 0.3\n\
        [[forces]]\nname = \"tie\"\ntype = \"spring-damper\"\nbodies = [\"a\", \"b\"]\n\
        at = [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0]]\nstiffness = 50.0\nfree_length = 0.3\n\
        [simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    let failures = switching_runs_growing(
        &[
            text, spatial, ball, disk, pushed, landing, &joint, spinning, rolled, pair,
        ],
        "impact",
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Generalized-α and ALI3-P on models with limits that stay free (held free by `Frictional`,
/// which would stop the run at a bound): a planar and a spatial rod swinging from horizontal to
/// the other horizontal between stops at −3.5 and 0.5 rad; after 50 rounds of the simulator's
/// loop, 300 more allocate nothing.
#[test]
fn implicit_methods_with_free_limits_allocate_nothing_per_step() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    COUNTED.with(|c| c.set(true));
    let planar = "[scene]\ngravity = [0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = { rod = 1.0 }\nposition = [0.5, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0]\n\
        limits = [-3.5, 0.5]\n[simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    let spatial = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08, 0.08]\nposition = [0.5, 0.0, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
        axis = [0.0, -1.0, 0.0]\nlimits = [-3.5, 0.5]\n[simulation]\nstep = 1e-3\noutput_every = 0.01\n";
    let mut failures = Vec::new();
    let mut ran = 0;
    for text in [planar, spatial] {
        let base = dalembert::Scene::from_toml(text, "rod").unwrap();
        for entry in METHODS.iter().filter(|e| e.applies == Applies::AugmentedIndex3) {
            let mut scene = base.clone();
            scene.settings.method = Method::of(entry);
            let (count, _) = loop_after_warm_up(&scene, 50, 300);
            ran += 1;
            if count > 0 {
                failures.push(format!("{}: {count} allocations in 300 rounds", entry.name));
            }
        }
    }
    assert_eq!(ran, 4, "generalized-α and ALI3-P, planar and spatial");
    assert!(failures.is_empty(), "{failures:#?}");
}
