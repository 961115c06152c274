//! Sensitivities of a run's outputs to scene parameters against numbers from elsewhere: the
//! closed-form motion of a mass on a spring-damper differentiated in its stiffness, damping and
//! mass; a pendulum whose motion does not depend on its mass (`∂θ/∂m = 0`) and whose pin reaction
//! is proportional to it (`∂F/∂m = F/m`); the three formulations giving the same sensitivities of
//! a four-bar; a spatial pendulum's sensitivities against the difference of two whole runs.

use dalembert::{FormulationKind, Scene, SceneValue, SensitivityRequest};
use std::sync::atomic::AtomicBool;

const G: f64 = 9.81;

/// `tests/data/hanging-spring.toml`: a slider of mass `m` on a vertical guide, hanging from a
/// spring-damper (`k`, `c`, free length 1 m) fixed at the origin, released at rest at `y = −1`.
/// With `u = y + 1`: `m ü + c u̇ + k u = −m g`, `u(0) = u̇(0) = 0`, so
/// `u = u_e (1 − e^{−ζωt} (cos ω_d t + ζω/ω_d sin ω_d t))`, `u_e = −m g / k`.
fn slider_y(t: f64, m: f64, k: f64, c: f64) -> f64 {
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let ue = -m * G / k;
    let decay = (-zeta * w * t).exp();
    -1.0 + ue * (1.0 - decay * ((wd * t).cos() + zeta * w / wd * (wd * t).sin()))
}

/// The derivative of `f` at `x` by Richardson-extrapolated central differences (error
/// `O(h⁴)` = 1e-12 relative with `h = 1e-3 x`, round-off `1e-16 / 1e-3`): independent of the
/// simulator, from the closed form.
fn derivative(f: impl Fn(f64) -> f64, x: f64) -> f64 {
    let h = 1e-3 * x;
    let d = |h: f64| (f(x + h) - f(x - h)) / (2.0 * h);
    (4.0 * d(h / 2.0) - d(h)) / 3.0
}

fn hanging_spring(settings: &[(&str, SceneValue)]) -> Scene {
    let scene = Scene::from_path("tests/data/hanging-spring.toml").unwrap();
    let mut values = vec![
        ("simulation.end", SceneValue::Number(1.0)),
        ("simulation.output_every", SceneValue::Number(0.01)),
    ];
    values.extend(settings.iter().cloned());
    scene.with_values(&values).unwrap()
}

/// The largest error of `got` against `want` over a run, relative to the largest `|want|`.
fn relative_error(got: &[f64], want: &[f64]) -> f64 {
    let scale = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    got.iter().zip(want).fold(0.0f64, |a, (g, w)| a.max((g - w).abs())) / scale
}

/// A run's formulation, method, step, other settings and the tolerance of its sensitivities.
type Setting<'a> = (&'a str, &'a str, f64, &'a [(&'a str, SceneValue)], f64);

#[test]
fn a_spring_damper_mass_has_the_sensitivities_of_its_closed_form() {
    // m = 2 kg, k = 400 N/m, c = 4 N·s/m: ω = 14.1 rad/s, ζ = 0.07, 2.2 periods in 1 s.
    // Tolerance 1e-7 of each derivative's scale: RK4 at 1 ms has a global error of about
    // (ωh)⁴ ωt / 120 ≈ 5e-9 in the motion and its derivatives, dopri5 at rtol 1e-10 less; the
    // central differences with δ = 1e-4 p add about δ² = 1e-8 times the derivative's own
    // curvature in p (measured 1.9e-8 for the mass, 5e-9 for k and c). Generalized-α (second
    // order, ρ∞ = 1: no damping) and ALI3-P (trapezoidal) at 0.1 ms have a phase error of about
    // (ωh)² ωt / 12 ≈ 2e-6 in the motion and its derivatives: 1e-5.
    let (m, k, c) = (2.0, 400.0, 4.0);
    let runs: [Setting; 6] = [
        ("augmented", "rk4", 1e-3, &[], 1e-7),
        ("embedding", "rk4", 1e-3, &[], 1e-7),
        ("amalgamated", "rk4", 1e-3, &[], 1e-7),
        (
            "augmented",
            "dopri5",
            1e-3,
            &[
                ("simulation.rtol", SceneValue::Number(1e-10)),
                ("simulation.atol", SceneValue::Number(1e-12)),
            ],
            1e-7,
        ),
        (
            "augmented",
            "generalized-alpha",
            1e-4,
            &[("simulation.rho_inf", SceneValue::Number(1.0))],
            1e-5,
        ),
        ("augmented", "ali3-p", 1e-4, &[], 1e-5),
    ];
    for (formulation, integrator, step, extra, tol) in runs {
        let mut values = vec![
            ("simulation.formulation", SceneValue::Text(formulation.into())),
            ("simulation.integrator", SceneValue::Text(integrator.into())),
            ("simulation.step", SceneValue::Number(step)),
        ];
        values.extend(extra.iter().cloned());
        let scene = hanging_spring(&values);
        let request = SensitivityRequest::new(
            &["forces.spring.stiffness", "forces.spring.damping", "bodies.slider.mass"],
            &["slider.y"],
        );
        let run = scene.sensitivities(&request, &AtomicBool::new(false)).unwrap();
        let stats = run.outcome.as_ref().unwrap();
        // The explicit methods carry the tangents through their stages on every step, with each
        // formulation's own factorization; the implicit ones take each step again on the changed
        // models.
        let carried = (stats.tangents_carried, stats.tangents_differenced);
        match integrator {
            "rk4" | "dopri5" => assert_eq!(carried, (stats.steps, 0), "{formulation} {integrator}"),
            _ => assert_eq!(carried, (0, stats.steps), "{formulation} {integrator}"),
        }
        let t = run.table.column("t").unwrap();
        assert_eq!(t.len(), 101);
        let y = run.table.column("slider.y").unwrap();
        let exact: Vec<f64> = t.iter().map(|&t| slider_y(t, m, k, c)).collect();
        assert!(
            relative_error(&y, &exact) < tol,
            "{formulation} {integrator}: the motion"
        );
        let exact = |which: usize| -> Vec<f64> {
            t.iter()
                .map(|&t| match which {
                    0 => derivative(|k| slider_y(t, m, k, c), k),
                    1 => derivative(|c| slider_y(t, m, k, c), c),
                    _ => derivative(|m| slider_y(t, m, k, c), m),
                })
                .collect()
        };
        for (j, p) in request.parameters.iter().enumerate() {
            let got = run.sensitivity("slider.y", p).unwrap();
            let err = relative_error(&got, &exact(j));
            assert!(
                err < tol,
                "{formulation} {integrator}: d(slider.y)/d({p}) off by {err:.2e}"
            );
        }
    }
}

#[test]
fn a_pendulum_moves_as_its_mass_says_and_carries_it_in_its_pin() {
    // A rigid body pinned at a point moves independently of its mass (the equation of motion
    // divides by it), so ∂θ/∂m = 0; the pin's reaction is proportional to the mass, so
    // ∂F/∂m = F/m at every output time. Tolerance 1e-7 (the derivative's scale: F/m ≈ 10):
    // the motion does not change with m and the reaction is linear in it, so the central
    // differences are exact but for round-off (1e-16 / δ per step, δ = 1e-4 kg).
    for formulation in FormulationKind::ALL {
        let scene = Scene::from_path("scenes/pendulum.toml")
            .unwrap()
            .with_values(&[
                ("simulation.end", 2.0.into()),
                ("simulation.formulation", formulation.name().into()),
            ])
            .unwrap();
        let request = SensitivityRequest::new(
            &["bodies.rod.mass"],
            &["rod.angle", "rod.omega", "pivot.fx", "pivot.fy"],
        );
        let run = scene.sensitivities(&request, &AtomicBool::new(false)).unwrap();
        run.outcome.as_ref().unwrap();
        for c in ["rod.angle", "rod.omega"] {
            let d = run.sensitivity(c, "bodies.rod.mass").unwrap();
            let worst = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(worst < 1e-7, "{} d({c})/dm = {worst:.2e}", formulation.name());
        }
        for c in ["pivot.fx", "pivot.fy"] {
            let d = run.sensitivity(c, "bodies.rod.mass").unwrap();
            let f = run.table.column(c).unwrap();
            let err = d.iter().zip(&f).fold(0.0f64, |a, (d, f)| a.max((d - f / 1.0).abs()));
            assert!(err < 1e-7, "{} d({c})/dm against F/m: {err:.2e}", formulation.name());
        }
    }
}

/// The masses of a scene's bodies as parameters, `bodies.NAME.mass`.
fn mass_paths(scene: &Scene) -> Vec<String> {
    let names = scene.model.body_names();
    names.iter().map(|b| format!("bodies.{b}.mass")).collect()
}

/// A model whose bodies' inertia follows from their mass and shape moves the same when every mass
/// is scaled by one factor, and its reactions scale by it: by Euler's theorem on homogeneous
/// functions, `Σ_k m_k ∂y/∂m_k = 0` for every motion column and `= F` for every reaction. Each
/// term is itself far from zero (the distribution of mass moves the mechanism), so the sum tests
/// every sensitivity at once. Returns the largest sum against the largest term, motion and
/// reactions.
fn homogeneity(scene: &Scene, motion: &[&str], reactions: &[&str]) -> (f64, f64) {
    let paths = mass_paths(scene);
    let masses: Vec<f64> = paths.iter().map(|p| scene.number_at(p).unwrap()).collect();
    let of: Vec<&str> = motion.iter().chain(reactions).copied().collect();
    let params: Vec<&str> = paths.iter().map(String::as_str).collect();
    let run = scene
        .sensitivities(&SensitivityRequest::new(&params, &of), &AtomicBool::new(false))
        .unwrap();
    run.outcome.as_ref().unwrap();
    let worst = |c: &str, reaction: bool| -> f64 {
        let own = run.table.column(c).unwrap();
        let terms: Vec<Vec<f64>> = (paths.iter().zip(&masses))
            .map(|(p, m)| run.sensitivity(c, p).unwrap().iter().map(|d| m * d).collect())
            .collect();
        let scale = terms.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(
            scale > 1e-3,
            "{c}: the terms are {scale:.1e}: the test would test nothing"
        );
        (0..own.len())
            .map(|i| {
                let sum: f64 = terms.iter().map(|t| t[i]).sum();
                (sum - if reaction { own[i] } else { 0.0 }).abs() / scale
            })
            .fold(0.0, f64::max)
    };
    let m = motion.iter().map(|c| worst(c, false)).fold(0.0, f64::max);
    let r = reactions.iter().map(|c| worst(c, true)).fold(0.0, f64::max);
    (m, r)
}

#[test]
fn a_four_bar_scaled_in_mass_moves_the_same_in_every_formulation() {
    // The shipped four-bar (rods: inertia m L² / 12) for 2 s at RK4 1 ms with projection. The sums
    // are 0 and F up to the differences' truncation (δ² ≈ 1e-8 relative) and round-off: 1e-6 of
    // the largest term. The three formulations' sensitivities agree to 1e-6 of their scale
    // (each differentiates its own numerical solution; the solutions agree to round-off).
    let mut first: Option<Vec<f64>> = None;
    for formulation in FormulationKind::ALL {
        let scene = Scene::from_path("scenes/four-bar.toml")
            .unwrap()
            .with_values(&[
                ("simulation.end", 2.0.into()),
                ("simulation.output_every", 0.05.into()),
                ("simulation.formulation", formulation.name().into()),
            ])
            .unwrap();
        let (m, r) = homogeneity(
            &scene,
            &["coupler.angle", "rocker.omega", "coupler.x"],
            &["A.fx", "C.fy"],
        );
        assert!(
            m < 1e-6 && r < 1e-6,
            "{}: motion {m:.2e}, reactions {r:.2e}",
            formulation.name()
        );
        let request = SensitivityRequest::new(&["bodies.coupler.mass"], &["rocker.angle"]);
        let run = scene.sensitivities(&request, &AtomicBool::new(false)).unwrap();
        let stats = run.outcome.as_ref().unwrap();
        assert_eq!(
            (stats.tangents_carried, stats.tangents_differenced),
            (stats.steps, 0),
            "{}: RK4 carries the tangents on every step",
            formulation.name()
        );
        let d = run.sensitivity("rocker.angle", "bodies.coupler.mass").unwrap();
        match &first {
            None => first = Some(d),
            Some(a) => {
                let err = relative_error(&d, a);
                assert!(err < 1e-6, "{} against augmented: {err:.2e}", formulation.name());
            }
        }
    }
}

#[test]
fn a_spatial_chain_scaled_in_mass_moves_the_same() {
    // The shipped spatial chain of 16 boxes on spherical joints (inertia from mass and box),
    // 1.5 s at its own settings in absolute coordinates: the same homogeneity, 1e-6, through the Euler parameters'
    // normalization and the spatial projection.
    let scene = Scene::from_path("scenes/spatial-chain-16.toml")
        .unwrap()
        .with_values(&[
            ("simulation.end", 1.5.into()),
            ("simulation.output_every", 0.05.into()),
            ("simulation.coordinates", "absolute".into()),
        ])
        .unwrap();
    let names = scene.model.body_names();
    let last = names.last().unwrap();
    let motion = [format!("{last}.x"), format!("{last}.z"), format!("{}.wy", names[3])];
    let motion: Vec<&str> = motion.iter().map(String::as_str).collect();
    let (m, r) = homogeneity(&scene, &motion, &[]);
    assert!(m < 1e-6 && r < 1e-6, "motion {m:.2e}");
}

/// The largest difference between a run's sensitivity and the central difference of two whole
/// runs on the scenes with `p ± δ`, relative to the largest `|∂c/∂p|`.
fn against_two_runs(scene: &Scene, parameter: &str, column: &str, relative: f64) -> f64 {
    let p = scene.number_at(parameter).unwrap();
    let delta = relative * p;
    let run = scene
        .sensitivities(
            &SensitivityRequest::new(&[parameter], &[column]),
            &AtomicBool::new(false),
        )
        .unwrap();
    run.outcome.as_ref().unwrap();
    let got = run.sensitivity(column, parameter).unwrap();
    let side = |p: f64| {
        let changed = scene.with_values(&[(parameter, SceneValue::Number(p))]).unwrap();
        let recorded = changed.record(&AtomicBool::new(false));
        recorded.outcome.unwrap();
        recorded.table.column(column).unwrap()
    };
    let (plus, minus) = (side(p + delta), side(p - delta));
    let want: Vec<f64> = plus.iter().zip(&minus).map(|(a, b)| (a - b) / (2.0 * delta)).collect();
    relative_error(&got, &want)
}

/// A run's method, step, stabilization and the bar of its sensitivities against two whole runs.
type Against<'a> = (&'a str, f64, &'a str, f64);

#[test]
fn every_method_and_formulation_agrees_with_two_whole_runs() {
    // The sensitivity is the derivative of the run's own numerical solution; two whole runs on
    // the scenes with p ± δ (δ = 1e-4 p) difference the same solution, computed apart (their own
    // steps, projections and dopri5's step choices). Planar (the four-bar) and spatial (the
    // slider-crank-3d: Euler parameters, a closed loop, light bodies whose tangents grow large),
    // every formulation, 1 s.
    // - Without projection the two are the same derivative: they differ by the differences'
    //   truncation and round-off (about 1e-10 a stage), by dopri5's step choices (rtol 1e-10
    //   over 2δ) and the whole runs' own δ² (measured ≤ 7e-8): bar 1e-6.
    // - With projection the tangent follows the run's projection by its linearization at the
    //   projected state, which differs from the derivative of the projection of the stepped state
    //   by the order of the step's drift: RK4 and dopri5 measured ≤ 2.9e-6, bar 1e-5 (the
    //   first-order symplectic Euler drifts by h² a step: 1.8e-4 on the four-bar, not tested).
    // - Generalized-α and ALI3-P take each step again on the changed models (four-bar: measured
    //   1.9e-6 and 5.6e-9): bar 1e-5.
    let settings: [Against; 8] = [
        ("rk4", 1e-3, "none", 1e-6),
        ("dopri5", 1e-3, "none", 1e-6),
        ("symplectic-euler", 1e-4, "none", 1e-6),
        ("rk4", 1e-3, "projection", 1e-5),
        ("dopri5", 1e-3, "projection", 1e-5),
        ("generalized-alpha", 1e-3, "projection", 1e-5),
        ("ali3-p", 1e-3, "projection", 1e-5),
        ("generalized-alpha", 1e-3, "none", 1e-5),
    ];
    let cases = [
        ("scenes/four-bar.toml", "bodies.coupler.mass", "rocker.angle"),
        ("scenes/slider-crank-3d.toml", "bodies.rod.mass", "slider.x"),
    ];
    let mut failures = Vec::new();
    for (path, parameter, column) in cases {
        for formulation in FormulationKind::ALL {
            for &(integrator, step, stabilization, bar) in &settings {
                let implicit = matches!(integrator, "generalized-alpha" | "ali3-p");
                if implicit && (formulation != FormulationKind::Augmented || path.contains("3d")) {
                    continue;
                }
                let values = [
                    ("simulation.end", SceneValue::Number(1.0)),
                    ("simulation.output_every", SceneValue::Number(0.05)),
                    ("simulation.formulation", formulation.name().into()),
                    ("simulation.integrator", SceneValue::Text(integrator.into())),
                    ("simulation.step", SceneValue::Number(step)),
                    ("simulation.stabilization", SceneValue::Text(stabilization.into())),
                    ("simulation.rtol", SceneValue::Number(1e-10)),
                    ("simulation.atol", SceneValue::Number(1e-12)),
                ];
                let values = if integrator == "dopri5" {
                    &values[..]
                } else {
                    &values[..6]
                };
                let scene = Scene::from_path(path).unwrap().with_values(values).unwrap();
                let err = against_two_runs(&scene, parameter, column, 1e-4);
                if err > bar {
                    let name = formulation.name();
                    failures.push(format!(
                        "{path} {name} {integrator} {stabilization}: {err:.2e} (bar {bar:e})"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_spatial_slider_crank_keeps_its_sensitivity_where_the_tangent_grows() {
    // The slider-crank-3d over 10 s without projection, RK4 at 1 ms: the light crank's and
    // rod's tangents grow to where a difference of the changed models at `y ± δ S` (δ = 1e-4 p)
    // leaves the linear range; that scheme was 0.44 of the derivative off two whole runs
    // (`docs/sensitivities.md`). Differencing the tangent's direction with its own small step and
    // the parameter at the run's state: measured 1.9e-5 (the whole runs' own difference is
    // δ-independent to 3 digits). Bar 1e-4.
    let scene = Scene::from_path("scenes/slider-crank-3d.toml")
        .unwrap()
        .with_values(&[
            ("simulation.end", SceneValue::Number(10.0)),
            ("simulation.output_every", SceneValue::Number(0.05)),
            ("simulation.stabilization", SceneValue::Text("none".into())),
        ])
        .unwrap();
    let err = against_two_runs(&scene, "bodies.rod.mass", "slider.x", 1e-4);
    assert!(err < 1e-4, "{err:.2e}");
}
