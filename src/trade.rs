//! The speed–accuracy trade of `dalembert trade`: every formulation × integrator × stabilization
//! × step (or tolerance) on one scene, measured against a tight reference run
//! (Dormand–Prince at rtol = atol = 1e-12 with projection, augmented). The command line writes and
//! plots it; the Python package returns it.

use crate::scene::unknown_name;
use crate::{Coordinates, FormulationKind, Scene, SimulationError};
use dalembert_integrators::{
    method_names, Applies, IntegrationError, IntegratorOptions, Method, Stabilization, TradeAxis,
};
use std::sync::atomic::{AtomicBool, Ordering};

/// The grid of settings to try. [`TradeGrid::default`] is the command line's default grid.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeGrid {
    /// Formulation names, and [`JOINT`]: the scene in joint coordinates (a spatial tree of
    /// revolute and prismatic joints; `docs/joint-coordinates.md`), where the three formulations
    /// are one equation and so one entry. The formulations run in absolute coordinates.
    pub formulations: Vec<String>,
    /// Integrator names (of [`dalembert_integrators::METHODS`]).
    pub integrators: Vec<String>,
    /// Stabilizations of the fixed-step methods that do not keep the constraints themselves
    /// (adaptive methods run with projection).
    pub stabilizations: Vec<String>,
    /// Steps of the fixed-step methods (s).
    pub steps: Vec<f64>,
    /// Tolerances of the adaptive method (rtol = atol).
    pub tolerances: Vec<f64>,
    /// End time of every run (s); `None`: the scene's, at most 5 s.
    pub end: Option<f64>,
    /// Comparison interval (s); `None`: the larger of the scene's output interval and the largest
    /// step.
    pub every: Option<f64>,
}

/// The grid's name for the joint-coordinate runs (`joint/rk4`, …).
pub const JOINT: &str = "joint";

impl Default for TradeGrid {
    /// Every formulation and the joint coordinates (dropped by [`trade`] for a model that cannot
    /// take them), every method, stabilization and the steps and tolerances below.
    fn default() -> Self {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<String>>();
        let mut formulations = names(FormulationKind::NAMES);
        formulations.push(JOINT.to_string());
        TradeGrid {
            formulations,
            integrators: names(&method_names()),
            stabilizations: names(Stabilization::NAMES),
            steps: vec![1e-2, 3e-3, 1e-3, 3e-4],
            tolerances: vec![1e-4, 1e-6, 1e-8, 1e-10],
            end: None,
            every: None,
        }
    }
}

/// One run of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeRun {
    /// `formulation/integrator/treatment`.
    pub method: String,
    /// Step (fixed-step methods) or tolerance (dopri5).
    pub parameter: f64,
    /// Wall time of the integration loop (s); NaN for a failed run.
    pub time_s: f64,
    /// Right-hand-side evaluations.
    pub evaluations: u64,
    /// Largest deviation of any coordinate or velocity from the reference at the comparison
    /// times; `None` for a failed run.
    pub error: Option<f64>,
    /// Largest `|C|`.
    pub constraint: f64,
    /// Largest `|ΔE|` (J).
    pub energy: f64,
    /// `ok`, or the failure.
    pub status: String,
}

/// The outcome of [`trade`].
#[derive(Debug, Clone, PartialEq)]
pub struct Trade {
    /// End time of every run (s).
    pub end: f64,
    /// Comparison interval (s).
    pub every: f64,
    /// What the errors are measured against, in words.
    pub reference: String,
    /// Every run of the grid, in grid order (those run before an interruption, the last of them
    /// with the status `interrupted at t = …`, when [`Trade::interrupted`]).
    pub runs: Vec<TradeRun>,
    /// True when the cancellation flag stopped the grid part way ([`trade_cancellable`]).
    pub interrupted: bool,
    /// Indices of the runs on the Pareto front (no other run both faster and more accurate),
    /// fastest first.
    pub front: Vec<usize>,
}

impl Trade {
    /// The fastest run whose error is within `band`.
    pub fn best_within(&self, band: f64) -> Option<&TradeRun> {
        self.runs
            .iter()
            .filter(|r| r.error.is_some_and(|e| e <= band))
            .min_by(|x, y| x.time_s.total_cmp(&y.time_s))
    }
}

/// Wall time, evaluations, largest |C| and largest energy change of a finished run.
type Outcome = (f64, u64, f64, f64);

/// Samples `[q, q̇]` at the comparison times, and the outcome or the failure.
fn samples(
    scene: &Scene,
    kind: (FormulationKind, Coordinates),
    opts: IntegratorOptions,
    end: f64,
    cancel: &AtomicBool,
) -> (Vec<Vec<f64>>, Result<Outcome, SimulationError>) {
    let (out, r, _) = samples_bridged(scene, kind, opts, end, cancel);
    (out, r)
}

/// [`samples`], and the singular positions the run bridged (`Statistics::bridges`).
fn samples_bridged(
    scene: &Scene,
    (kind, coordinates): (FormulationKind, Coordinates),
    opts: IntegratorOptions,
    end: f64,
    cancel: &AtomicBool,
) -> (Vec<Vec<f64>>, Result<Outcome, SimulationError>, u64) {
    let mut sim = scene.simulation();
    sim.formulation = kind;
    sim.coordinates = coordinates;
    sim.integrator = opts;
    sim.end = end;
    let mut out = Vec::new();
    let res = sim.run_cancellable(&mut |s| out.push([s.q, s.qd].concat()), cancel);
    let bridges = res.as_ref().map(|st| st.bridges).unwrap_or(0);
    let r = res.map(|st| {
        (
            st.wall_time.as_secs_f64(),
            st.evaluations,
            st.max_constraint_violation,
            st.max_energy_change,
        )
    });
    (out, r, bridges)
}

/// The runs of `g`: formulation, label, options and parameter, from each method's
/// [`TradeAxis`] in the registry. Unknown names are one-line errors.
/// A run of the grid: formulation and coordinates, label, options, step or tolerance.
type GridRun = ((FormulationKind, Coordinates), String, IntegratorOptions, f64);

fn runs_of(g: &TradeGrid) -> Result<Vec<GridRun>, String> {
    for (values, what) in [(&g.steps, "steps"), (&g.tolerances, "tolerances")] {
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(format!("{what}: every value must be positive and finite, got {v}"));
        }
    }
    let stabilizations = g
        .stabilizations
        .iter()
        .map(|t| {
            Stabilization::parse(t)
                .map(|s| (t.as_str(), s))
                .ok_or_else(|| unknown_name("stabilization", t, Stabilization::NAMES))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut out = Vec::new();
    for f in &g.formulations {
        let joint = f == JOINT;
        let kind = match joint {
            true => (FormulationKind::Augmented, Coordinates::Joint),
            false => {
                let mut names = FormulationKind::NAMES.to_vec();
                names.push(JOINT);
                let k = FormulationKind::parse(f).ok_or_else(|| unknown_name("formulation", f, &names))?;
                (k, Coordinates::Absolute)
            }
        };
        for i in &g.integrators {
            let method = Method::named(i).ok_or_else(|| unknown_name("integrator", i, &method_names()))?;
            let entry = method.entry();
            // A method for the augmented index-3 equations only would, with another formulation,
            // measure the augmented method under another name.
            if entry.applies == Applies::AugmentedIndex3 && kind.0 != FormulationKind::Augmented {
                continue;
            }
            match entry.trade {
                TradeAxis::Tolerances(keys) => {
                    for &tol in &g.tolerances {
                        let mut m = method;
                        for key in keys {
                            m = m.with(key, tol)?;
                        }
                        let mut o =
                            IntegratorOptions::fixed(m, 1e-3, 1.0).with_stabilization(Stabilization::projection());
                        // Steps limited only by the tolerance (dense output gives the samples).
                        o.max_step = f64::INFINITY;
                        // In joint coordinates there is nothing to project: no suffix.
                        let label = match joint {
                            true => format!("{f}/{}", entry.name),
                            false => format!("{f}/{}/projection", entry.name),
                        };
                        out.push((kind, label, o, tol));
                    }
                }
                // Without constraint equations every stabilization is the same run: one variant.
                TradeAxis::Steps if entry.keeps_constraints || joint => {
                    for &h in &g.steps {
                        let o = IntegratorOptions::fixed(method, h, 1.0);
                        out.push((kind, format!("{f}/{}", entry.name), o, h));
                    }
                }
                _ => {
                    for &(t, st) in &stabilizations {
                        for &h in &g.steps {
                            let o = IntegratorOptions::fixed(method, h, 1.0).with_stabilization(st);
                            out.push((kind, format!("{f}/{}/{t}", entry.name), o, h));
                        }
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Runs the grid `g` on `scene`; `progress(done, total)` is called after every run. Errors: a name
/// or value of the grid that is not valid, or a reference run that fails (each grid run that
/// fails is a row with its status instead).
pub fn trade(scene: &Scene, g: &TradeGrid, progress: &mut dyn FnMut(usize, usize)) -> Result<Trade, String> {
    trade_cancellable(scene, g, progress, &AtomicBool::new(false))
}

/// [`trade`] that stops once `cancel` is set (e.g. by Ctrl-C): the run in progress stops at its
/// next step and is the last row (status `interrupted at t = …`), no further run starts, and the
/// result says [`Trade::interrupted`]. Set during the reference run, it is an error.
pub fn trade_cancellable(
    scene: &Scene,
    g: &TradeGrid,
    progress: &mut dyn FnMut(usize, usize),
    cancel: &AtomicBool,
) -> Result<Trade, String> {
    let mut g = g.clone();
    if let Some(problem) = crate::scene::joint_coordinates_problem(&scene.model) {
        if g.formulations.iter().any(|f| f == JOINT) {
            // The default grid offers joint coordinates where the model takes them; a grid that
            // names them for a model that does not is an error.
            if g.formulations != TradeGrid::default().formulations {
                return Err(format!("formulation '{JOINT}': {problem}"));
            }
            g.formulations.retain(|f| f != JOINT);
        }
    }
    let g = &g;
    let grid = runs_of(g)?;
    let end = g.end.unwrap_or(scene.settings.end.min(5.0));
    let largest_step = g.steps.iter().cloned().fold(0.0f64, f64::max);
    let every = g.every.unwrap_or(scene.settings.output_every.max(largest_step));
    if !(end.is_finite() && end > 0.0 && every.is_finite() && every > 0.0) {
        return Err("--end and --every must be positive".into());
    }
    let with_every = |mut o: IntegratorOptions| {
        o.output_every = every;
        if o.max_step.is_finite() {
            o.max_step = every;
        }
        o
    };
    let ref_opts = with_every(
        IntegratorOptions::fixed(Method::dopri5(1e-12, 1e-12), 1e-4, 1.0)
            .with_stabilization(Stabilization::Projection { tolerance: 1e-12 }),
    );
    let absolute = (FormulationKind::Augmented, Coordinates::Absolute);
    let (mut reference, status, bridges) = samples_bridged(scene, absolute, ref_opts, end, cancel);
    if let Err(e) = &status {
        if let Some(t) = e.interrupted_at() {
            return Err(format!(
                "interrupted during the reference run, at t = {}: no run of the grid was made",
                crate::output::shortest(t)
            ));
        }
    }
    let mut reference_name = "dopri5 at rtol = atol = 1e-12".to_string();
    // An adaptive step does not cross a singular position of a closed chain to its tolerance: it
    // stops there, or bridges it with steps checked to about 31 × the tolerances only. The
    // reference is then a fixed-step RK4 with projection at 1/50 of the smallest grid step (at most
    // 1e-4 s), which steps across.
    let why = match status {
        Ok(_) if bridges > 0 => Some(format!("dopri5 bridged {bridges} singular position(s)")),
        Ok(_) => None,
        Err(SimulationError::Integration(f)) if matches!(f.error, IntegrationError::SingularPass { .. }) => {
            Some(f.to_string())
        }
        Err(e) => return Err(format!("reference run failed: {e}")),
    };
    if let Some(e) = why {
        let smallest = g.steps.iter().cloned().fold(f64::INFINITY, f64::min);
        let h = (smallest / 50.0).min(1e-4);
        let opts = with_every(
            IntegratorOptions::fixed(Method::rk4(), h, 1.0)
                .with_stabilization(Stabilization::Projection { tolerance: 1e-12 }),
        );
        let (r, status) = samples(scene, absolute, opts, end, cancel);
        status.map_err(|e2| format!("reference run failed: {e}; and the fixed-step fallback: {e2}"))?;
        reference = r;
        reference_name = format!(
            "rk4 with projection at h = {h:.1e} s: the scene passes a singular position, which dopri5 does not cross to its tolerance"
        );
    }
    let total = grid.len();
    let mut runs = Vec::with_capacity(total);
    for (k, (kind, method, opts, parameter)) in grid.into_iter().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            break;
        }
        let (got, res) = samples(scene, kind, with_every(opts), end, cancel);
        runs.push(match res {
            Ok((time_s, evaluations, constraint, energy)) => TradeRun {
                method,
                parameter,
                time_s,
                evaluations,
                error: Some(
                    got.iter()
                        .zip(&reference)
                        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                        .fold(0.0f64, f64::max),
                ),
                constraint,
                energy,
                status: "ok".into(),
            },
            Err(e) => TradeRun {
                method,
                parameter,
                time_s: f64::NAN,
                evaluations: 0,
                error: None,
                constraint: f64::NAN,
                energy: f64::NAN,
                status: match e.interrupted_at() {
                    Some(t) => format!("interrupted at t = {}", crate::output::shortest(t)),
                    None => e.to_string(),
                },
            },
        });
        progress(k + 1, total);
    }
    let front = pareto(&runs);
    Ok(Trade {
        reference: reference_name,
        end,
        every,
        runs,
        front,
        interrupted: cancel.load(Ordering::Relaxed),
    })
}

/// Indices of the runs on the Pareto front (no other run both faster and more accurate).
fn pareto(runs: &[TradeRun]) -> Vec<usize> {
    let mut ok: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].error.is_some()).collect();
    ok.sort_by(|&a, &b| runs[a].time_s.total_cmp(&runs[b].time_s));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in ok {
        let e = runs[i].error.unwrap_or(f64::INFINITY);
        if e < best {
            best = e;
            front.push(i);
        }
    }
    front
}
