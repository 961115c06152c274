//! dalembert's side of the `shared/anchors` protocol: times and accuracy on the anchor scenes, one
//! JSON record per line to `$ANCHORS_OUT` (or stdout), in the fields of `shared/anchors/README.md`.
//! `ANCHORS_PART=planar` (the default): chain of N rods, four-bar, slider-crank, errors against
//! `results/reference.json`; `ANCHORS_PART=spatial`: chain3d, heavytop, slidercrank3d
//! (`dalembert_testkit::spatial`), errors against `results/reference_spatial.json`. Run from the
//! anchors folder:
//!
//! ```sh
//! ANCHORS_EXTRA="cargo run --release --manifest-path $PROJECT/Cargo.toml --example anchors" python run_all.py
//! ```
//!
//! Options (environment): `ANCHORS_QUICK=1` limits chains to N ≤ 8 and repeats once;
//! `ANCHORS_NS=16,64` runs only those chain sizes;
//! `ANCHORS_FRONT=1` runs the work–precision variants instead (RK4 at steps of 2 to 50 ms,
//! Dormand–Prince with projection at tolerances 1e-3 to 1e-9): with the same error measure and
//! timing as the engines, they give dalembert's front against the engines' points at 1 ms. Run it
//! as a second `ANCHORS_EXTRA` command:
//!
//! ```sh
//! ANCHORS_EXTRA="$BIN; ANCHORS_FRONT=1 $BIN" python run_all.py   # BIN=<project>/target/release/examples/anchors
//! ```

use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, IntegratorOptions, Method, Stabilization};
use dalembert::system::Formulation;
use dalembert::system::MultibodySystem;
use dalembert_testkit::anchors::state_errors;
use dalembert_testkit::{mechanisms, spatial};
use std::io::Write;
use std::sync::Arc;
use std::time::Instant;

/// A scene's system and consistent initial state.
struct Mechanism {
    model: Arc<dyn MultibodySystem>,
    q: Vec<f64>,
    qd: Vec<f64>,
    /// Spatial (errors against 13-column reference rows).
    spatial: bool,
    /// The model in joint coordinates, when it is a tree of revolute and prismatic joints.
    joints: Option<dalembert::spatial::JointCoordinates>,
}

impl From<mechanisms::Mechanism> for Mechanism {
    fn from(m: mechanisms::Mechanism) -> Self {
        Mechanism {
            model: m.model,
            q: m.q,
            qd: m.qd,
            spatial: false,
            joints: None,
        }
    }
}

impl From<Arc<dalembert::spatial::Model>> for Mechanism {
    fn from(m: Arc<dalembert::spatial::Model>) -> Self {
        let (q, qd) = m.initial_state();
        let joints = m.joint_coordinates().ok();
        Mechanism {
            model: m,
            q,
            qd,
            spatial: true,
            joints,
        }
    }
}

struct Variant {
    name: &'static str,
    /// Run the model in joint coordinates (spatial trees; other scenes skip the variant).
    joint_space: bool,
    integrator: &'static str,
    options: IntegratorOptions,
}

fn variants() -> Vec<Variant> {
    let h = 1e-3;
    let proj = Stabilization::Projection { tolerance: 1e-10 };
    vec![
        Variant {
            name: "augmented RK4",
            joint_space: false,
            integrator: "RK4",
            options: IntegratorOptions::fixed(Method::rk4(), h, 0.01),
        },
        Variant {
            name: "joint coordinates RK4",
            joint_space: true,
            integrator: "RK4",
            options: IntegratorOptions::fixed(Method::rk4(), h, 0.01),
        },
        Variant {
            name: "joint coordinates GenAlpha",
            joint_space: true,
            integrator: "GeneralizedAlpha",
            options: IntegratorOptions::fixed(Method::generalized_alpha(0.9), h, 0.01),
        },
        Variant {
            name: "augmented RK4+proj",
            joint_space: false,
            integrator: "RK4",
            options: IntegratorOptions::fixed(Method::rk4(), h, 0.01).with_stabilization(proj),
        },
        Variant {
            name: "augmented Euler+proj",
            joint_space: false,
            integrator: "Euler",
            options: IntegratorOptions::fixed(Method::symplectic_euler(), h, 0.01).with_stabilization(proj),
        },
        Variant {
            name: "augmented GenAlpha",
            joint_space: false,
            integrator: "GeneralizedAlpha",
            options: IntegratorOptions::fixed(Method::generalized_alpha(0.9), h, 0.01),
        },
    ]
}

/// The work–precision variants (`ANCHORS_FRONT`): explicit methods at larger steps and an adaptive
/// method at several tolerances, output every 10 ms (or every step, above 10 ms) so that t = 1 s
/// is a sample.
fn front_variants() -> Vec<Variant> {
    let proj = Stabilization::Projection { tolerance: 1e-10 };
    let rk4 = |name: &'static str, h: f64| Variant {
        name,
        joint_space: false,
        integrator: "RK4",
        options: IntegratorOptions::fixed(Method::rk4(), h, h.max(0.01)),
    };
    let dopri = |name: &'static str, tol: f64| {
        let mut options = IntegratorOptions::fixed(Method::dopri5(tol, tol), 1e-3, 0.01).with_stabilization(proj);
        // Steps as long as the error allows (dense output gives the 10 ms samples).
        options.max_step = 0.1;
        Variant {
            name,
            joint_space: false,
            integrator: "DOPRI5",
            options,
        }
    };
    vec![
        rk4("augmented RK4 h=2ms", 2e-3),
        rk4("augmented RK4 h=5ms", 5e-3),
        rk4("augmented RK4 h=10ms", 1e-2),
        rk4("augmented RK4 h=20ms", 2e-2),
        rk4("augmented RK4 h=50ms", 5e-2),
        dopri("augmented DOPRI5+proj tol=1e-3", 1e-3),
        dopri("augmented DOPRI5+proj tol=1e-5", 1e-5),
        dopri("augmented DOPRI5+proj tol=1e-7", 1e-7),
        dopri("augmented DOPRI5+proj tol=1e-9", 1e-9),
    ]
}

/// The chain sizes: `ANCHORS_NS` (comma-separated, like the engine scripts' `--ns`) or all.
fn anchors_ns() -> Vec<usize> {
    match std::env::var("ANCHORS_NS") {
        Ok(list) => list.split(',').filter_map(|n| n.trim().parse().ok()).collect(),
        Err(_) => vec![1, 2, 4, 8, 16, 32, 64],
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// µs per forward-dynamics evaluation (median of batches).
fn fd_us((model, q, qd): (&Arc<dyn MultibodySystem>, &[f64], &[f64])) -> f64 {
    let mut f = Augmented::with_defaults(model.clone()).expect("formulation");
    let (n, m) = (qd.len(), model.num_equations());
    let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
    let reps = (20000 / (n + 1)).max(20);
    let batches: Vec<f64> = (0..7)
        .map(|_| {
            let t0 = Instant::now();
            for k in 0..reps {
                // A new time at every call (the scenes do not depend on it): the formulation keeps
                // the constraint values of an unchanged state, which would skip their evaluation.
                f.accelerations(1e-12 * k as f64, q, qd, None, &mut qdd, &mut lam)
                    .expect("evaluation");
            }
            t0.elapsed().as_secs_f64() * 1e6 / reps as f64
        })
        .collect();
    median(batches)
}

struct RunResult {
    /// `None` when the run failed (the message is reported instead).
    failure: Option<String>,
    sim_s: f64,
    at_one: (Vec<f64>, Vec<f64>),
    de_10s: f64,
    de_max: f64,
    cviol: f64,
    /// Steps taken over the 10 s.
    steps: u64,
}

/// A system with an initial state `(q, q̇)`.
type Start = (Arc<dyn MultibodySystem>, Vec<f64>, Vec<f64>);

/// The system and initial state a variant runs: the scene's, or its joint-coordinate form.
fn system_of(mech: &Mechanism, joint_space: bool) -> Option<Start> {
    if !joint_space {
        return Some((mech.model.clone(), mech.q.clone(), mech.qd.clone()));
    }
    let jc = mech.joints.as_ref()?;
    let (q, qd) = jc.initial_state();
    Some((jc.system(), q, qd))
}

fn simulate(mech: &Mechanism, joint_space: bool, opts: &IntegratorOptions) -> Option<RunResult> {
    let (model, q0, qd0) = system_of(mech, joint_space)?;
    let mut f = Augmented::with_defaults(model).expect("formulation");
    let e0 = f.energy(0.0, &q0, &qd0).total();
    let mut at_one = (Vec::new(), Vec::new());
    let mut de_max = 0.0f64;
    let mut de_last = 0.0;
    let mut frames = mech.joints.as_ref().map(|jc| jc.frames()).unwrap_or_default();
    let result = integrate(&mut f, 0.0, 10.0, &q0, &qd0, opts, &mut |s| {
        if (s.t - 1.0).abs() < 1e-9 {
            at_one = match (&mech.joints, joint_space) {
                // The errors are measured on the model's absolute coordinates.
                (Some(jc), true) => {
                    let (mut q, mut qd) = (mech.q.clone(), mech.qd.clone());
                    jc.absolute(s.q, s.qd, &mut frames, &mut q, &mut qd);
                    (q, qd)
                }
                _ => (s.q.to_vec(), s.qd.to_vec()),
            };
        }
        de_max = de_max.max((s.energy - e0).abs());
        de_last = s.energy - e0;
    });
    let (failure, stats) = match result {
        Ok(s) => (None, s),
        Err(e) => (Some(format!("stopped at {}", e.error)), *e.statistics),
    };
    Some(RunResult {
        failure,
        sim_s: stats.wall_time.as_secs_f64(),
        at_one,
        de_10s: de_last,
        de_max,
        cviol: stats.max_constraint_violation,
        steps: stats.steps,
    })
}

/// Max abs errors (positions and angles; velocities) against the reference bodies at t = 1 s.
fn errors(mech: &Mechanism, (q, qd): &(Vec<f64>, Vec<f64>), reference: &serde_json::Value) -> (f64, f64) {
    if mech.spatial {
        let rows: Vec<Vec<f64>> = serde_json::from_value(reference.clone()).unwrap_or_default();
        if rows.is_empty() || q.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        return spatial::state_errors(q, qd, &rows);
    }
    let rows: Vec<[f64; 6]> = reference
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|b| {
            let r: Vec<f64> = b.as_array().into_iter().flatten().filter_map(|v| v.as_f64()).collect();
            r.try_into().ok()
        })
        .take(q.len() / 3)
        .collect();
    state_errors(q, qd, &rows)
}

fn main() {
    let quick = std::env::var("ANCHORS_QUICK").is_ok();
    let is_spatial = std::env::var("ANCHORS_PART").is_ok_and(|p| p == "spatial");
    let reference_file = if is_spatial {
        "results/reference_spatial.json"
    } else {
        "results/reference.json"
    };
    let reference: serde_json::Value = std::fs::read_to_string(reference_file)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or(serde_json::Value::Null);
    let mut out: Box<dyn Write> = match std::env::var("ANCHORS_OUT") {
        Ok(p) => Box::new(std::fs::File::create(p).expect("ANCHORS_OUT writable")),
        Err(_) => Box::new(std::io::stdout()),
    };
    let mut scenes: Vec<(String, usize, Mechanism)> = Vec::new();
    for &n in &anchors_ns() {
        if quick && n > 8 {
            continue;
        }
        if is_spatial {
            scenes.push(("chain3d".into(), n, spatial::chain3d(n).into()));
        } else {
            let chain = mechanisms::chain(1.0, 1.0, &vec![0.0; n], &vec![0.0; n], &[]);
            scenes.push(("chain".into(), n, chain.into()));
        }
    }
    if is_spatial {
        scenes.push(("heavytop".into(), 1, spatial::heavy_top().into()));
        scenes.push(("slidercrank3d".into(), 1, spatial::slider_crank_3d().into()));
    } else {
        let four_bar = mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false);
        scenes.push(("fourbar".into(), 1, four_bar.into()));
        let slider_crank = mechanisms::slider_crank(std::f64::consts::FRAC_PI_3, 0.0);
        scenes.push(("slidercrank".into(), 1, slider_crank.into()));
    }
    for (scene, n, mech) in &scenes {
        let key = format!("{scene}/{n}");
        let front = std::env::var("ANCHORS_FRONT").is_ok();
        // One evaluation timed once per scene and coordinates, not per variant.
        let mut fd_of: [Option<f64>; 2] = [None, None];
        for v in if front { front_variants() } else { variants() } {
            let Some((model, q, qd)) = system_of(mech, v.joint_space) else {
                continue;
            };
            let fd = *fd_of[usize::from(v.joint_space)].get_or_insert_with(|| fd_us((&model, &q, &qd)));
            let repeats = if quick { 1 } else { 3 };
            let runs: Vec<RunResult> = (0..repeats)
                .filter_map(|_| simulate(mech, v.joint_space, &v.options))
                .collect();
            let sim_s = median(runs.iter().map(|r| r.sim_s).collect());
            let r = &runs[0];
            let (ep, ev) = errors(mech, &r.at_one, &reference["scenes"][&key]["bodies"]);
            let has_ref = !reference["scenes"][&key]["bodies"].is_null();
            let mut rec = serde_json::json!({
                "engine": "dalembert",
                "variant": v.name,
                "scene": scene,
                "N": n,
                "integrator": v.integrator,
                "fd_us": fd,
                "fd_call": if v.joint_space { "Augmented::accelerations (joint coordinates: articulated-body algorithm)" } else { "Augmented::accelerations" },
                "sim_s": sim_s,
                "sim_native_s": sim_s,
                "err_pos_1s": if has_ref { serde_json::json!(ep) } else { serde_json::Value::Null },
                "err_vel_1s": if has_ref { serde_json::json!(ev) } else { serde_json::Value::Null },
                "dE_10s": r.de_10s,
                "dE_max": r.de_max,
                "cviol_max": r.cviol,
                "dt": v.options.step,
                "steps": r.steps,
            });
            if let Some(msg) = &r.failure {
                // A failed run has no meaningful time or accuracy: report the cause instead.
                let short: String = msg.chars().take(160).collect();
                rec["sim_s"] = serde_json::Value::Null;
                rec["sim_native_s"] = serde_json::Value::Null;
                rec["dE_10s"] = serde_json::Value::Null;
                rec["note"] = serde_json::json!(short);
            }
            writeln!(out, "{rec}").expect("write");
            eprintln!("{key} {}: {:.4} s, err {ep:.2e}/{ev:.2e}", v.name, sim_s);
        }
    }
}
