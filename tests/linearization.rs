//! Linearization against closed forms and against the nonlinear motion: a compound pendulum in
//! its angle (`θ̈ = −ω² sin(θ − θ_h)`, at rest and at a moving state away from rest), a mass on a
//! spring-damper pushed by an input (`A = [0 1; −k/m −c/m]`, `B = [0; 1/m]`, a reaction's `D`),
//! a double pendulum of point masses (`A`'s eigenvalues `±i ω`, `ω² = (g/L)(2 ∓ √2)`), the three
//! formulations giving the same model away from equilibrium, and small motions of the nonlinear
//! runs (planar and spatial) that the linear model predicts to second order.

use dalembert::{About, FormulationKind, LinearizeOptions, Scene};
use nalgebra::DMatrix;

const G: f64 = 9.81;

fn options(inputs: &[&str], outputs: &[&str], states: &[&str], about: About) -> LinearizeOptions {
    let owned = |x: &[&str]| x.iter().map(|s| s.to_string()).collect();
    LinearizeOptions {
        inputs: owned(inputs),
        outputs: owned(outputs),
        states: owned(states),
        about,
    }
}

/// `‖a − b‖∞ ≤ tol · (1 + ‖b‖∞)`.
fn close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64) -> bool {
    a.shape() == b.shape() && (a - b).amax() <= tol * (1.0 + b.amax())
}

#[test]
fn a_pendulum_linearized_in_its_angle_is_its_closed_form_at_rest_and_in_motion() {
    // The shipped pendulum (uniform rod 1 kg, 1 m, centre of mass d from the pivot): in its angle,
    // θ̈ = −ω² sin(θ − θ_h), ω² = m g d / (m L²/12 + m d²), θ_h the hanging angle. Linearized:
    // A = [0 1; −ω² cos(θ − θ_h) 0], drift [θ̇, −ω² sin(θ − θ_h)]. Tolerance 1e-9 relative:
    // the extrapolated central differences' error is O(h⁴) = 1e-12 with h = 1e-3, round-off
    // 1e-16 / h.
    let scene = Scene::from_path("scenes/pendulum.toml").unwrap();
    let d = (0.25f64 * 0.25 + 0.433 * 0.433).sqrt();
    let w2 = G * d / (1.0 / 12.0 + d * d);
    let lin = scene
        .linearize(&options(&[], &[], &["rod.angle"], About::Equilibrium))
        .unwrap();
    assert_eq!(lin.states, ["rod.angle", "rod.omega"]);
    let expected = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w2, 0.0]);
    assert!(close(&lin.a, &expected, 1e-9), "A = {}", lin.a);
    assert!(lin.drift.iter().all(|x| x.abs() < 1e-9), "drift {:?}", lin.drift);
    // Coordinate partitioning's own choice: a different state, the same eigenvalues ±i ω.
    let auto = scene.linearize(&LinearizeOptions::default()).unwrap();
    let s = auto.a.complex_eigenvalues();
    for z in s.iter() {
        assert!(
            z.re.abs() < 1e-8 && (z.im.abs() - w2.sqrt()).abs() < 1e-9 * w2.sqrt(),
            "{s}"
        );
    }
    // Away from rest, swinging: θ = θ_h + 1.1, θ̇ = 2 rad/s. The body vector from the pivot to the
    // centre of mass, s' = R(θ_file)ᵀ p_file, gives the state exactly (the pivot at the origin).
    let theta_h = lin.q[2];
    let (theta_file, p_file) = (scene.q[2], [scene.q[0], scene.q[1]]);
    let rot = |a: f64, v: [f64; 2]| [a.cos() * v[0] - a.sin() * v[1], a.sin() * v[0] + a.cos() * v[1]];
    let s_body = rot(-theta_file, p_file);
    let (theta, omega) = (theta_h + 1.1, 2.0);
    let p = rot(theta, s_body);
    let q = vec![p[0], p[1], theta];
    let qd = vec![-omega * p[1], omega * p[0], omega];
    let about = About::State {
        t: 0.0,
        q,
        qd,
        inputs: Vec::new(),
    };
    let moving = scene.linearize(&options(&[], &[], &["rod.angle"], about)).unwrap();
    let expected = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -w2 * 1.1f64.cos(), 0.0]);
    assert!(close(&moving.a, &expected, 1e-9), "A = {}", moving.a);
    assert!((moving.drift[0] - omega).abs() < 1e-12, "{:?}", moving.drift);
    assert!(
        (moving.drift[1] + w2 * 1.1f64.sin()).abs() < 1e-9 * w2,
        "{:?}",
        moving.drift
    );
}

#[test]
fn a_pushed_mass_on_a_spring_damper_has_its_closed_form_state_space() {
    // tests/data/hanging-spring.toml (m = 2 kg, k = 400 N/m, c = 4 N·s/m) with an input pushing
    // the slider along its guide (y) and across it (x): A = [0 1; −k/m −c/m], B = [0; 1/m];
    // outputs slider.y and slider.vy: C = I, D = 0; the guide's reaction across it (the force the
    // slider exerts on the ground, docs/sign-conventions.md): guide.fx = u, so C = 0, D = 1.
    // Tolerance 1e-9 relative (exact linear model: the differences' only error is round-off).
    let (m, k, c) = (2.0, 400.0, 4.0);
    let text = std::fs::read_to_string("tests/data/hanging-spring.toml").unwrap()
        + "\n[[forces]]\nname = \"push\"\ntype = \"force\"\nbody = \"slider\"\nfx = { input = \"u\" }\nfy = { input = \"u\" }\n";
    let scene = Scene::from_toml(&text, "pushed spring").unwrap();
    let lin = scene
        .linearize(&options(
            &["u"],
            &["slider.y", "slider.vy", "guide.fx"],
            &["slider.y"],
            About::Equilibrium,
        ))
        .unwrap();
    assert_eq!(lin.states, ["slider.y", "slider.vy"]);
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -k / m, -c / m]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0 / m]);
    let cc = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
    let d = DMatrix::from_row_slice(3, 1, &[0.0, 0.0, 1.0]);
    assert!(close(&lin.a, &a, 1e-9), "A = {}", lin.a);
    assert!(close(&lin.b, &b, 1e-9), "B = {}", lin.b);
    assert!(close(&lin.c, &cc, 1e-9), "C = {}", lin.c);
    assert!(close(&lin.d, &d, 1e-9), "D = {}", lin.d);
    // The equilibrium's outputs: y = −1 − m g / k at rest, nothing across the guide.
    let y = -1.0 - m * G / k;
    assert!((lin.outputs_at[0] - y).abs() < 1e-12, "{:?}", lin.outputs_at);
    assert!(lin.outputs_at[2].abs() < 1e-10, "{:?}", lin.outputs_at);
}

/// Two point masses `m` on massless links of length 1 (tiny inertias 1e-12: 1e-12 relative).
fn double_pendulum(start_angle: f64) -> String {
    let (s, c) = start_angle.sin_cos();
    format!(
        r#"[scene]
gravity = [0.0, -9.81]
[[bodies]]
name = "upper"
mass = 1.0
inertia = 1e-12
position = [{s}, {mc}]
angle = {start_angle}
[[bodies]]
name = "lower"
mass = 1.0
inertia = 1e-12
position = [{s2}, {mc2}]
angle = {start_angle}
[[joints]]
name = "shoulder"
type = "revolute"
bodies = ["ground", "upper"]
at = [0.0, 0.0]
[[joints]]
name = "elbow"
type = "revolute"
bodies = ["upper", "lower"]
at = [{s}, {mc}]
"#,
        mc = -c,
        s2 = 2.0 * s,
        mc2 = -2.0 * c
    )
}

#[test]
fn a_double_pendulum_linearized_has_its_closed_form_frequencies_as_eigenvalues() {
    // A's eigenvalues are ±i ω with ω² = (g/L)(2 ∓ √2) (1e-9 relative: the inertias of 1e-12
    // and the differences' O(h⁴)), whichever coordinates partitioning keeps.
    let scene = Scene::from_toml(&double_pendulum(0.3), "double pendulum").unwrap();
    let lin = scene.linearize(&LinearizeOptions::default()).unwrap();
    let sqrt2 = 2.0f64.sqrt();
    let mut got: Vec<f64> = lin.a.complex_eigenvalues().iter().map(|z| z.im.abs()).collect();
    got.sort_by(f64::total_cmp);
    let (w1, w2) = ((G * (2.0 - sqrt2)).sqrt(), (G * (2.0 + sqrt2)).sqrt());
    for (g, w) in got.iter().zip([w1, w1, w2, w2]) {
        assert!((g - w).abs() < 1e-9 * w, "{got:?}, expected {w1} {w2}");
    }
}

#[test]
fn every_formulation_gives_the_same_linear_model_away_from_equilibrium() {
    // The shipped four-bar at its initial state (moving, driven by gravity), in the crank angle,
    // with reactions as outputs: augmented, embedding and amalgamated agree to 1e-8 relative
    // (each formulation's accelerations agree to round-off; the differences amplify that by
    // 1/h = 1e3 and extrapolation).
    let mut scene = Scene::from_path("scenes/four-bar.toml").unwrap();
    let outputs = ["B.fx", "C.fy", "rocker.angle", "coupler.omega"];
    let mut models = Vec::new();
    for name in ["augmented", "embedding", "amalgamated"] {
        scene.settings.formulation = FormulationKind::parse(name).unwrap();
        let about = About::State {
            t: 0.0,
            q: scene.q.clone(),
            // Any velocities: assembled to the constraints (the least change).
            qd: (0..scene.qd.len()).map(|k| 0.5 * (1.3 * k as f64).sin()).collect(),
            inputs: Vec::new(),
        };
        models.push((
            name,
            scene
                .linearize(&options(&[], &outputs, &["crank.angle"], about))
                .unwrap(),
        ));
    }
    let (_, first) = &models[0];
    assert!(
        first.a.amax() > 1.0 && first.c.amax() > 1.0,
        "A = {}, C = {}",
        first.a,
        first.c
    );
    for (name, lin) in &models[1..] {
        assert!(
            close(&lin.a, &first.a, 1e-8),
            "{name}: A = {} against {}",
            lin.a,
            first.a
        );
        assert!(
            close(&lin.c, &first.c, 1e-8),
            "{name}: C = {} against {}",
            lin.c,
            first.c
        );
        let drift = DMatrix::from_column_slice(2, 1, &lin.drift);
        assert!(close(&drift, &DMatrix::from_column_slice(2, 1, &first.drift), 1e-10));
    }
}

/// The nonlinear run from the operating point moved by `C δx₀` against the linear model's
/// prediction `y₀ + C e^{A T} δx₀`, with `outputs` every position and velocity column (so that
/// `C` gives the first-order state in the model's coordinates). Returns the largest difference
/// and the largest predicted change.
fn linear_against_nonlinear(scene: &Scene, dx0: &[f64], end: f64) -> (f64, f64) {
    let sim = scene.simulator().unwrap();
    let names: Vec<String> = sim.columns().to_vec();
    let (n_q, n_v) = (scene.q.len(), scene.qd.len());
    let per = (n_q + n_v) / scene.model.num_bodies();
    let state: Vec<&str> = names[1..]
        .iter()
        .take(per * scene.model.num_bodies())
        .map(String::as_str)
        .collect();
    let lin = scene.linearize(&options(&[], &state, &[], About::Equilibrium)).unwrap();
    let dx = DMatrix::from_column_slice(dx0.len(), 1, dx0);
    let dy0 = &lin.c * &dx;
    // The perturbed state in the model's coordinates (unit Euler parameters again: a change of
    // second order).
    let per_q = n_q / scene.model.num_bodies();
    let (mut q, mut qd) = (Vec::new(), Vec::new());
    for k in 0..state.len() {
        let value = lin.outputs_at[k] + dy0[k];
        if k % per < per_q {
            q.push(value);
        } else {
            qd.push(value);
        }
    }
    if per_q == 7 {
        for e in q.chunks_mut(7) {
            let norm = e[3..].iter().map(|x| x * x).sum::<f64>().sqrt();
            e[3..].iter_mut().for_each(|x| *x /= norm);
        }
    }
    let mut run = scene.simulator().unwrap();
    run.set_state(&q, &qd).unwrap();
    run.advance_to(end).unwrap();
    let predicted = &lin.c * (&lin.a * end).exp() * &dx;
    let (mut worst, mut size) = (0.0f64, 0.0f64);
    for (k, name) in state.iter().enumerate() {
        let got = run.value(name).unwrap() - lin.outputs_at[k];
        worst = worst.max((got - predicted[k]).abs());
        size = size.max(predicted[k].abs());
    }
    (worst, size)
}

#[test]
fn small_motions_of_the_nonlinear_runs_follow_the_linear_model_to_second_order() {
    // A perturbation of 1e-6 about the equilibrium, integrated by Dormand–Prince at 1e-12 for
    // 0.7 s and by the linear model (e^{A T}): they agree to second order, |δ|² ≈ 1e-12 (bar:
    // 1e-10, against changes of ~1e-6: an error of 1e-4 in A would show as 1e-10).
    let tight = "\n[simulation]\nintegrator = \"dopri5\"\nrtol = 1e-12\natol = 1e-12\n";
    // Planar: the double pendulum with a damped spring on its lower mass.
    let planar = double_pendulum(0.0)
        + "[[forces]]\nname = \"spring\"\ntype = \"spring-damper\"\nbodies = [\"ground\", \"lower\"]\nat = [[0.7, -2.0], [0.0, 0.0]]\nstiffness = 30.0\ndamping = 0.8\nfree_length = 0.5\n"
        + tight;
    // Spatial: a body hanging on a spherical joint (its axes the global ones at rest, so the
    // CSV's global angular velocities are its own to first order).
    let spatial = r#"
[scene]
gravity = [0.0, 0.0, -9.81]
[[bodies]]
name = "bob"
mass = 3.0
inertia = [0.05, 0.07, 0.02]
position = [0.0, 0.0, -0.8]
[[joints]]
name = "pivot"
type = "spherical"
bodies = ["ground", "bob"]
at = [0.0, 0.0, 0.0]
"#
    .to_string()
        + tight;
    for (text, dx0) in [
        (planar, vec![1e-6, -0.6e-6, 0.4e-6, 0.9e-6]),
        (spatial, vec![1e-6, -0.7e-6, 0.5e-6, 0.3e-6, 0.8e-6, -1e-6]),
    ] {
        let scene = Scene::from_toml(&text, "perturbed").unwrap();
        let (worst, size) = linear_against_nonlinear(&scene, &dx0, 0.7);
        assert!(size > 1e-7, "the perturbation moved the outputs by {size}");
        assert!(worst < 1e-10, "linear and nonlinear differ by {worst} (changes {size})");
    }
}

#[test]
fn bad_requests_are_refused_in_one_line_naming_the_cause() {
    let scene = Scene::from_path("scenes/pendulum.toml").unwrap();
    let message = |o: LinearizeOptions| scene.linearize(&o).unwrap_err().to_string();
    let cases = [
        (
            options(&["push"], &[], &[], About::Equilibrium),
            "unknown input 'push': the scene has no inputs",
        ),
        (
            options(&[], &["rod.z"], &[], About::Equilibrium),
            "unknown output column 'rod.z'",
        ),
        (
            options(&[], &[], &["rod.phi"], About::Equilibrium),
            "unknown state 'rod.phi'",
        ),
        (
            options(&[], &[], &["rod.x", "rod.y"], About::Equilibrium),
            "2 states named where the model has 1 degree(s) of freedom",
        ),
        (
            options(
                &[],
                &[],
                &[],
                About::State {
                    t: 0.0,
                    q: vec![0.0; 2],
                    qd: vec![0.0; 3],
                    inputs: Vec::new(),
                },
            ),
            "the model has 3 positions and 3 velocities; 2 and 3 were given",
        ),
    ];
    for (o, expected) in cases {
        let got = message(o);
        assert!(got.starts_with("linearize: ") && got.contains(expected), "{got}");
        assert!(!got.contains('\n'), "{got}");
    }
    // A parallelogram four-bar (links of 1 m, pivots 1 m apart) turned 0.5 rad, linearized at
    // its folded state, every link on the x axis: the constraint Jacobian loses rank there.
    let scene = Scene::from_toml(&parallelogram(0.5), "parallelogram").unwrap();
    let folded = Scene::from_toml(&parallelogram(0.0), "folded").unwrap();
    let got = scene
        .linearize(&options(
            &[],
            &[],
            &[],
            About::State {
                t: 0.0,
                q: folded.q.clone(),
                qd: folded.qd.clone(),
                inputs: Vec::new(),
            },
        ))
        .unwrap_err()
        .to_string();
    assert!(got.contains("singular position"), "{got}");
}

/// A parallelogram four-bar of unit links, crank and rocker at `angle`.
fn parallelogram(angle: f64) -> String {
    let (c, s) = (angle.cos(), angle.sin());
    format!(
        r#"[scene]
gravity = [0.0, -9.81]
[[bodies]]
name = "crank"
mass = 1.0
shape = {{ rod = 1.0 }}
position = [{cx}, {cy}]
angle = {angle}
[[bodies]]
name = "coupler"
mass = 1.0
shape = {{ rod = 1.0 }}
position = [{kx}, {s}]
[[bodies]]
name = "rocker"
mass = 1.0
shape = {{ rod = 1.0 }}
position = [{rx}, {cy}]
angle = {angle}
[[joints]]
name = "A"
type = "revolute"
bodies = ["ground", "crank"]
at = [0.0, 0.0]
[[joints]]
name = "B"
type = "revolute"
bodies = ["crank", "coupler"]
at = [{c}, {s}]
[[joints]]
name = "C"
type = "revolute"
bodies = ["coupler", "rocker"]
at = [{c1}, {s}]
[[joints]]
name = "D"
type = "revolute"
bodies = ["ground", "rocker"]
at = [1.0, 0.0]
"#,
        cx = 0.5 * c,
        cy = 0.5 * s,
        kx = c + 0.5,
        rx = 1.0 + 0.5 * c,
        c1 = 1.0 + c
    )
}
