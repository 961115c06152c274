//! Spatial scene files (`docs/scenes.md`, "Spatial scenes") against numbers from elsewhere:
//!
//! - the shipped `scenes/heavy-top.toml` and `scenes/slider-crank-3d.toml`, and the generated
//!   chain of 4 (`examples/spatial_chain.rs`), written from the anchors' README, against the
//!   anchors' reference states at t = 1 s (`tests/data/anchors_reference_spatial.json`, scipy DOP853
//!   at 1e-12 on minimal coordinates), read from the output columns `<body>.x … <body>.wz` with
//!   every formulation (Dormand–Prince at 1e-11; tolerances as in `tests/spatial_anchors_reference.rs`:
//!   1e-7 on positions and orientation angles, 1e-6 on velocities);
//! - the scene's initial energy against the anchors' E0;
//! - each way of writing an orientation against the rotation matrix built by hand;
//! - the shapes' inertia against textbook facts (a cube's `m a²/6`, a sphere's `2/5 m r²`, a
//!   cylinder with `l = √3 r` having equal moments `m r²/2`);
//! - inverse dynamics of a driven hinge written as a scene against `τ = J_P θ̈ − m g a cos θ`.

use dalembert::output::Table;
use dalembert::{FormulationKind, Scene, SceneValue};
use nalgebra::{Matrix3, Rotation3, Vector3};
use std::sync::atomic::AtomicBool;

fn reference(scene: &str) -> Vec<Vec<f64>> {
    let json: serde_json::Value = serde_json::from_str(include_str!("data/anchors_reference_spatial.json")).unwrap();
    serde_json::from_value(json["scenes"][scene]["bodies"].clone()).unwrap()
}

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// The scene run to 1 s with Dormand–Prince at 1e-11 and `formulation`; the output table.
fn run_to_one_second(scene: &Scene, formulation: FormulationKind) -> Table {
    let s = scene
        .with_values(&[
            ("simulation.end", 1.0.into()),
            ("simulation.integrator", "dopri5".into()),
            ("simulation.rtol", 1e-11.into()),
            ("simulation.atol", 1e-11.into()),
            ("simulation.step", 1e-4.into()),
            ("simulation.output_every", 0.5.into()),
            ("simulation.formulation", SceneValue::Text(formulation.name().into())),
        ])
        .unwrap();
    let rec = s.record(&AtomicBool::new(false));
    rec.outcome
        .unwrap_or_else(|e| panic!("{} {}: {e}", scene.name, formulation.name()));
    rec.table
}

/// Largest position / orientation-angle error and velocity error of the last row of `table`
/// against the reference rows `[x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz]`.
fn errors(table: &Table, bodies: &[String], rows: &[Vec<f64>]) -> (f64, f64) {
    let last = table.row(table.rows() - 1);
    assert_eq!(last[0], 1.0);
    let col = |b: &str, c: &str| last[table.index(&format!("{b}.{c}")).unwrap()];
    let (mut pos, mut vel) = (0.0f64, 0.0f64);
    for (b, r) in bodies.iter().zip(rows) {
        for (k, c) in ["x", "y", "z"].iter().enumerate() {
            pos = pos.max((col(b, c) - r[k]).abs());
        }
        // Angle between the orientations: 2 acos |e · e_ref| (unit quaternions, either sign).
        let dot: f64 = ["e0", "e1", "e2", "e3"]
            .iter()
            .enumerate()
            .map(|(k, c)| col(b, c) * r[3 + k])
            .sum();
        pos = pos.max(2.0 * dot.abs().min(1.0).acos());
        for (k, c) in ["vx", "vy", "vz", "wx", "wy", "wz"].iter().enumerate() {
            vel = vel.max((col(b, c) - r[7 + k]).abs());
        }
    }
    (pos, vel)
}

#[test]
fn spatial_scene_files_match_the_anchors_reference() {
    let chain = dalembert_testkit::spatial::chain3d_toml(4, 10.0);
    let scenes = [
        (
            "heavytop/1",
            Scene::from_path(root().join("scenes/heavy-top.toml")).unwrap(),
            5435.6968,
        ),
        (
            "slidercrank3d/1",
            Scene::from_path(root().join("scenes/slider-crank-3d.toml")).unwrap(),
            0.766908,
        ),
        ("chain3d/4", Scene::from_toml(&chain, "chain3d-4").unwrap(), 0.0),
    ];
    for (name, scene, e0) in &scenes {
        // The anchors' README gives E0 to 8 significant digits (the velocities it lists are
        // rounded to 6).
        let sys = scene.model.as_system();
        let energy = sys.kinetic_energy(&scene.q, &scene.qd) + sys.potential_energy(0.0, &scene.q);
        assert!(
            (energy - e0).abs() <= 1e-6 * e0.abs().max(1.0),
            "{name}: E0 = {energy}, README {e0}"
        );
        let bodies = scene.model.body_names();
        let rows = reference(name);
        assert_eq!(rows.len(), bodies.len(), "{name}");
        for f in FormulationKind::ALL {
            let (pos, vel) = errors(&run_to_one_second(scene, f), &bodies, &rows);
            assert!(
                pos < 1e-7 && vel < 1e-6,
                "{name} {}: position error {pos:e}, velocity error {vel:e}",
                f.name()
            );
        }
    }
}

/// A free body oriented by `orientation` (a TOML inline table); its rotation matrix.
fn oriented(orientation: &str) -> Matrix3<f64> {
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n[[bodies]]\nname = \"b\"\nmass = 1.0\ninertia = [1.0, 2.0, 2.5]\nposition = [0.0, 0.0, 0.0]\norientation = {orientation}\n"
    );
    let scene = Scene::from_toml(&text, "orientation").unwrap_or_else(|e| panic!("{orientation}: {e}"));
    let p = [scene.q[3], scene.q[4], scene.q[5], scene.q[6]];
    dalembert::spatial::euler_parameters::rotation(&p)
}

#[test]
fn every_way_of_writing_an_orientation_gives_the_rotation_built_by_hand() {
    let (a, b, c) = (0.3, -1.1, 2.0);
    // Rotations about the body's successive axes z, y', x'': A = Rz(a) Ry(b) Rx(c).
    let zyx = Rotation3::from_axis_angle(&Vector3::z_axis(), a)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), b)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), c);
    let u = Vector3::new(1.0, -2.0, 0.5);
    let about_u = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(u), 0.7);
    let quarter_z = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let cases: Vec<(String, Matrix3<f64>)> = vec![
        (
            format!("{{ sequence = \"zyx\", angles = [{a}, {b}, {c}] }}"),
            *zyx.matrix(),
        ),
        (
            format!(
                "{{ sequence = \"zyx\", degrees = [{}, {}, {}] }}",
                a.to_degrees(),
                b.to_degrees(),
                c.to_degrees()
            ),
            *zyx.matrix(),
        ),
        ("{ axis = [1.0, -2.0, 0.5], angle = 0.7 }".into(), *about_u.matrix()),
        ("{ axis = [0.0, 0.0, 2.0], degrees = 90 }".into(), quarter_z),
        (format!("{{ quaternion = [{h}, 0.0, 0.0, {h}] }}"), quarter_z),
        // Body x along global y, body y along −x (the given y need not be perpendicular).
        (
            "{ x_axis = [0.0, 3.0, 0.0], y_axis = [-1.0, 5.0, 0.0] }".into(),
            quarter_z,
        ),
    ];
    for (text, expected) in cases {
        let got = oriented(&text);
        // Round-off of a few products of sines and cosines.
        assert!((got - expected).amax() < 1e-14, "{text}: {got} != {expected}");
    }
}

#[test]
fn shapes_give_the_textbook_inertia() {
    let inertia = |shape: &str| {
        let text = format!(
            "[scene]\ngravity = [0.0, 0.0, 0.0]\n[[bodies]]\nname = \"b\"\nmass = 3.0\nshape = {shape}\nposition = [0.0, 0.0, 0.0]\n"
        );
        let scene = Scene::from_toml(&text, "shape").unwrap();
        scene.model.spatial().unwrap().bodies()[0].inertia
    };
    let (m, a, r) = (3.0, 0.4, 0.25);
    let cube = inertia(&format!("{{ box = [{a}, {a}, {a}] }}"));
    let sphere = inertia(&format!("{{ sphere = {r} }}"));
    let cylinder = inertia(&format!(
        "{{ cylinder = {{ radius = {r}, length = {} }} }}",
        3f64.sqrt() * r
    ));
    for (j, moment) in [
        (cube, m * a * a / 6.0),
        (sphere, 0.4 * m * r * r),
        (cylinder, 0.5 * m * r * r),
    ] {
        assert!(
            (j - Matrix3::identity() * moment).amax() < 1e-14 * moment,
            "{j} vs {moment}"
        );
    }
}

#[test]
fn inverse_dynamics_of_a_driven_hinge_scene_is_the_closed_form() {
    // A rod of mass m with its centre of mass a from a hinge about global y, driven at
    // θ = A sin(2π f t): τ = J_P θ̈ − m g a cos θ, J_P = J_yy + m a² (derivation in
    // tests/spatial_drivers.rs).
    let (m, a, g, j_yy, amp, f) = (2.0, 0.4, 9.81, 0.05, 0.8, 0.5);
    let text = format!(
        "[scene]\nname = \"driven hinge\"\ngravity = [0.0, 0.0, -{g}]\n\
         [[bodies]]\nname = \"rod\"\nmass = {m}\ninertia = [0.004, {j_yy}, {j_yy}]\nposition = [{a}, 0.0, 0.0]\n\
         [[joints]]\nname = \"hinge\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
         [[drivers]]\nname = \"motor\"\ntype = \"joint-angle\"\njoint = \"hinge\"\nfunction = {{ kind = \"harmonic\", amplitude = {amp}, frequency = {f} }}\n"
    );
    let scene = Scene::from_toml(&text, "driven hinge").unwrap();
    let (table, outcome) = scene.inverse_table(2.0, 0.01);
    outcome.unwrap();
    let w = 2.0 * std::f64::consts::PI * f;
    let j_p = j_yy + m * a * a;
    let (t, effort) = (table.column("t").unwrap(), table.column("motor.effort").unwrap());
    assert_eq!(t.len(), 201);
    for (t, e) in t.iter().zip(effort) {
        let theta = amp * (w * t).sin();
        let tau = j_p * (-w * w * theta) - m * g * a * theta.cos();
        // The kinematics are solved to ~1e-12; the torque is ~10 N·m.
        assert!((e - tau).abs() < 1e-8 * tau.abs().max(1.0), "t = {t}: {e} vs {tau}");
    }
}

#[test]
fn bricard_moves_with_the_degree_of_freedom_grubler_does_not_count() {
    let scene = Scene::from_path(root().join("scenes/bricard.toml")).unwrap();
    let r = scene.check().unwrap();
    // Grübler: 5 bodies x 6 - 6 revolute joints x 5 = 0; Bricard (1897): the loop moves with one
    // degree of freedom, so exactly one joint equation is redundant.
    assert_eq!(
        (
            r.coordinates,
            r.equations,
            r.rank,
            r.degrees_of_freedom,
            r.redundant.len()
        ),
        (30, 30, 29, 1, 1)
    );
    assert!(r.problems().is_empty(), "{:?}", r.problems());
    // Newton's law for the whole loop at t = 0 holds for any distribution of the redundant
    // reactions: Σ m a = F_E − F_O + M g (a joint's reaction acts on its first body from its
    // second: O joins the ground to rod1, E joins rod5 to the ground).
    let qdd = r.accelerations.clone().unwrap();
    let reaction = |name: &str| r.reactions.iter().find(|(n, _)| n == name).unwrap().1;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let ma: f64 = (0..5).map(|b| qdd[6 * b + k]).sum();
        let g = if k == 1 { -9.81 * 5.0 } else { 0.0 };
        let external = reaction(&format!("E.f{axis}")) - reaction(&format!("O.f{axis}")) + g;
        // Round-off of reactions of ~50 N.
        assert!((ma - external).abs() < 1e-10, "{axis}: Σ m a = {ma}, forces {external}");
    }
    let mut runs = Vec::new();
    for f in FormulationKind::ALL {
        let s = scene
            .with_values(&[
                ("simulation.end", 1.0.into()),
                ("simulation.formulation", SceneValue::Text(f.name().into())),
            ])
            .unwrap();
        let rec = s.record(&AtomicBool::new(false));
        rec.outcome.unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        let energy = rec.table.column("energy").unwrap();
        let change = energy.iter().fold(0.0f64, |m, e| m.max((e - energy[0]).abs()));
        // A conservative loop: RK4 at 1 ms changes T + V by its truncation error (measured
        // 1.3e-12 J over 2 s with the augmented formulation, 4.4e-12 J with the others; the
        // augmented one changed it by 1.2e-7 J while its minimum-norm path redid the structure
        // analysis at every evaluation).
        assert!(change < 1e-9, "{}: energy changed by {change:e} J", f.name());
        runs.push(rec.table);
    }
    // The loop really moves (rod3's centre travels), and the formulations agree on it to the
    // integration error (measured 2.5e-8 m over 2 s).
    let x3 = runs[0].column("rod3.x").unwrap();
    assert!(
        (x3[0] - x3[x3.len() - 1]).abs() > 0.05,
        "rod3.x {} -> {}",
        x3[0],
        x3[x3.len() - 1]
    );
    for other in &runs[1..] {
        for c in runs[0]
            .columns
            .iter()
            .filter(|c| c.ends_with(".x") || c.ends_with(".y") || c.ends_with(".z"))
        {
            let (a, b) = (runs[0].column(c).unwrap(), other.column(c).unwrap());
            let d = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(d < 1e-6, "{c}: formulations differ by {d:e}");
        }
    }
}

#[test]
fn rssr_rocker_follows_the_closed_form_and_the_motor_supplies_the_power() {
    // Crank a about z at A = 0: B = (a cos θ, a sin θ, 0); rocker c about x at D = (d, 0, h):
    // C = D + c (0, cos φ, sin φ). |C − B|² = L² with L² = d² + a² + c² + h² gives
    // P cos φ + Q sin φ = R, P = −2 a c sin θ, Q = 2 h c, R = 2 a d cos θ.
    let (a, c, d, h) = (0.2, 0.5, 1.0, 0.5);
    let phi_of = |theta: f64, near: f64| {
        let (p, q, r) = (-2.0 * a * c * theta.sin(), 2.0 * h * c, 2.0 * a * d * theta.cos());
        let (base, spread) = (q.atan2(p), (r / p.hypot(q)).acos());
        let wrap =
            |x: f64| (x - near + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI + near;
        let (x, y) = (wrap(base + spread), wrap(base - spread));
        if (x - near).abs() < (y - near).abs() {
            x
        } else {
            y
        }
    };
    let scene = Scene::from_path(root().join("scenes/rssr.toml")).unwrap();
    let r = scene.check().unwrap();
    // 3 x 6 − (5 + 3 + 3 + 5 + 1 driver) = 1: the coupler's spin about its own axis.
    assert_eq!(r.degrees_of_freedom, 1);
    let s = scene
        .with_values(&[("simulation.output_every", 1e-3.into()), ("simulation.end", 1.0.into())])
        .unwrap();
    let rec = s.record(&AtomicBool::new(false));
    rec.outcome.unwrap();
    // The motor does work: T + V is no first integral, so no energy warning (a driven model once
    // counted as conservative and was warned about its own motor's work).
    assert_eq!(rec.warning, None);
    let t = &rec.table;
    let col = |c: &str| t.column(c).unwrap();
    // A body's x axis in global components: the first column of its rotation matrix.
    let x_axis = |b: &str, k: usize| {
        let e: Vec<f64> = ["e0", "e1", "e2", "e3"]
            .iter()
            .map(|c| col(&format!("{b}.{c}"))[k])
            .collect();
        [
            e[0] * e[0] + e[1] * e[1] - e[2] * e[2] - e[3] * e[3],
            2.0 * (e[1] * e[2] + e[0] * e[3]),
            2.0 * (e[1] * e[3] - e[0] * e[2]),
        ]
    };
    let mut phi = 0.8f64.asin();
    let mut worst = 0.0f64;
    for k in 0..t.rows() {
        // The crank's x axis is (cos θ, sin θ, 0), the rocker's (0, cos φ, sin φ).
        let (xc, xr) = (x_axis("crank", k), x_axis("rocker", k));
        assert!(
            xc[2].abs() < 1e-9 && xr[0].abs() < 1e-9,
            "axes leave their planes: {xc:?} {xr:?}"
        );
        let theta = xc[1].atan2(xc[0]);
        phi = phi_of(theta, phi);
        let simulated = xr[2].atan2(xr[1]);
        let d = (simulated - phi + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        worst = worst.max(d.abs());
    }
    // Positions hold the constraints to the projection tolerance (1e-10).
    assert!(worst < 1e-8, "rocker angle off the closed form by {worst:e} rad");
    // Power balance: the motor's torque times the crank rate (2π rad/s) is d(T + V)/dt. The
    // derivative by the five-point stencil over 1 ms samples: truncation δ⁴ E⁽⁵⁾ / 30, about 2e-6 W
    // here (the three-point stencil's δ² E‴ / 6 is 5e-3 W, too coarse to test anything); round-off
    // ~ 1e-15 J / 1e-3 s. Tolerance 1e-4 W against powers of ~15 W.
    let (effort, energy) = (col("motor.effort"), col("energy"));
    let w = std::f64::consts::TAU;
    let mut largest = 0.0f64;
    for k in 2..t.rows() - 2 {
        let power = (-energy[k + 2] + 8.0 * energy[k + 1] - 8.0 * energy[k - 1] + energy[k - 2]) / 12e-3;
        largest = largest.max(power.abs());
        assert!(
            (effort[k] * w - power).abs() < 1e-4,
            "t = {}: motor {} W, dE/dt {} W",
            k as f64 * 1e-3,
            effort[k] * w,
            power
        );
    }
    assert!(largest > 1.0, "the motor does work: largest power {largest} W");
}

#[test]
fn a_body_placed_by_a_reference_point_is_the_same_body_placed_by_its_centre_of_mass() {
    // A rod (m = 2 kg, L = 1 m) hinged at the origin about y, turned 90° about x (its length along
    // body y, hanging along −z), swinging at 2 rad/s: once written at its centre of mass with the
    // inertia about it (m L²/12), once at the pivot with `center_of_mass` = (0, −L/2, 0) in body
    // axes and the inertia about the pivot (m L²/3, `inertia_about = "reference"`). The parallel
    // axis theorem and A c must turn the second into the first: the runs agree to round-off.
    let (m, l) = (2.0f64, 1.0f64);
    let body = |placement: &str, inertia: [f64; 3]| {
        format!(
            "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
             [[bodies]]\nname = \"rod\"\nmass = {m}\ninertia = {inertia:?}\n{placement}\n\
             orientation = {{ axis = [1.0, 0.0, 0.0], degrees = 90.0 }}\nangular_velocity = [0.0, 2.0, 0.0]\n\
             [[joints]]\nname = \"pivot\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n"
        )
    };
    let (across_c, across_o, along) = (m * l * l / 12.0, m * l * l / 3.0, 1e-3);
    let at_centre = body("position = [0.0, 0.0, -0.5]", [across_c, along, across_c]);
    let at_pivot = body(
        "position = [0.0, 0.0, 0.0]\ncenter_of_mass = [0.0, -0.5, 0.0]\ninertia_about = \"reference\"",
        [across_o, along, across_o],
    );
    let tables: Vec<Table> = [at_centre, at_pivot]
        .iter()
        .map(|text| {
            let s = Scene::from_toml(text, "rod")
                .unwrap()
                .with_values(&[("simulation.end", 2.0.into()), ("simulation.output_every", 0.1.into())])
                .unwrap();
            let rec = s.record(&AtomicBool::new(false));
            rec.outcome.unwrap();
            rec.table
        })
        .collect();
    assert_eq!(tables[0].columns, tables[1].columns);
    let mut worst = 0.0f64;
    for c in &tables[0].columns {
        let (a, b) = (tables[0].column(c).unwrap(), tables[1].column(c).unwrap());
        worst = a.iter().zip(&b).fold(worst, |w, (x, y)| w.max((x - y).abs()));
    }
    assert!(worst < 1e-12, "the two descriptions differ by {worst:e}");
    let z = tables[0].column("rod.z").unwrap();
    assert!(
        (z[0] + 0.5).abs() < 1e-12,
        "the centre of mass starts at z = −L/2: {}",
        z[0]
    );
    // The theorem itself: a rod's m L²/3 about its end is m L²/12 about its centre.
    let j = dalembert::spatial::body::inertia_about_center(
        m,
        &Matrix3::from_diagonal(&Vector3::new(across_o, along, across_o)),
        [0.0, -0.5, 0.0],
    );
    assert!((j - Matrix3::from_diagonal(&Vector3::new(across_c, along, across_c))).amax() < 1e-15);
}

#[test]
fn bricard_runs_with_dopri5_and_generalized_alpha() {
    // Until 2026-11-25 the augmented formulation with dopri5 stopped Bricard's loop at t = 0.31 s
    // ("rank 29 of 30": the structure analysis, redone at every evaluation, met a stage state off
    // the constraint manifold where the dropped equation looked inconsistent), and generalized-α
    // at 0.011 s (its Newton matrix kept the redundant row). The independent set is now kept, and
    // generalized-α masks the dropped row. Reference: the same loop by RK4 at 1 ms with the
    // augmented formulation; dopri5 (rtol 1e-6) agrees with it to 5e-12 m over 2 s (measured;
    // RK4's own error at 1 ms is of that order), so 1e-8 m is a loose bound that a lost branch or an
    // ignored joint (errors of centimetres) still fails.
    let scene = Scene::from_path(root().join("scenes/bricard.toml")).unwrap();
    let reference = scene.record(&AtomicBool::new(false));
    reference.outcome.unwrap();
    for f in FormulationKind::ALL {
        let s = scene
            .with_values(&[
                ("simulation.integrator", SceneValue::Text("dopri5".into())),
                ("simulation.formulation", SceneValue::Text(f.name().into())),
            ])
            .unwrap();
        let rec = s.record(&AtomicBool::new(false));
        rec.outcome.unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        assert_eq!(rec.table.rows(), reference.table.rows(), "{}", f.name());
        for c in ["rod1", "rod2", "rod3", "rod4", "rod5"]
            .iter()
            .flat_map(|b| ["x", "y", "z"].map(|k| format!("{b}.{k}")))
        {
            let (a, b) = (reference.table.column(&c).unwrap(), rec.table.column(&c).unwrap());
            let d = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(d < 1e-8, "{}: {c} differs from RK4 by {d:e} m", f.name());
        }
    }
    // Generalized-α (augmented) iterates on the independent equations: second order, so halving
    // the step divides its distance from the RK4 run by about 4 (measured 1.35e-6 and 3.4e-7 m).
    let mut errors = Vec::new();
    for step in [1e-3, 5e-4] {
        let s = scene
            .with_values(&[
                ("simulation.integrator", SceneValue::Text("generalized-alpha".into())),
                ("simulation.step", step.into()),
            ])
            .unwrap();
        let rec = s.record(&AtomicBool::new(false));
        rec.outcome
            .unwrap_or_else(|e| panic!("generalized-alpha, step {step}: {e}"));
        let mut worst = 0.0f64;
        for c in ["rod1", "rod2", "rod3", "rod4", "rod5"]
            .iter()
            .flat_map(|b| ["x", "y", "z"].map(|k| format!("{b}.{k}")))
        {
            let (a, b) = (reference.table.column(&c).unwrap(), rec.table.column(&c).unwrap());
            worst = a.iter().zip(&b).fold(worst, |m, (x, y)| m.max((x - y).abs()));
        }
        errors.push(worst);
    }
    let ratio = errors[0] / errors[1];
    assert!(
        errors[0] < 1e-5 && (3.5..4.5).contains(&ratio),
        "generalized-alpha: {errors:?}"
    );
}

/// Bricard's loop through its re-partition (rod 1 crossing x = 0 at t ≈ 3.75 s; issue #36), RK4 at
/// h = 1e-2 s with projection over 10 s, two swings: every formulation within 1e-5 m and 1e-4 J of
/// the augmented run. Until 2026-11-26 the embedding and amalgamated formulations re-chose their
/// partition at an RK4 stage state slightly off the loop's motion, where the redundancy that
/// holds only on the motion looked like full rank: the new partition had no independent
/// coordinate, the step was taken as if the loop were locked, and the velocities jumped by 36 %
/// (energy +3.84 J, a joint 1.3 m off). A new partition now keeps the number of independent
/// equations of the one it replaces. Measured after: 3.7e-7 m and 1.0e-6 J (RK4's own error at
/// this step against the augmented run, whose projection differs).
#[test]
fn bricard_re_partitions_without_a_jump() {
    let scene = Scene::from_path(root().join("scenes/bricard.toml"))
        .unwrap()
        .with_values(&[
            ("simulation.step", 1e-2.into()),
            ("simulation.end", 10.0.into()),
            ("simulation.stabilization", SceneValue::Text("projection".into())),
        ])
        .unwrap();
    let run = |f: FormulationKind| {
        let s = scene
            .with_values(&[("simulation.formulation", SceneValue::Text(f.name().into()))])
            .unwrap();
        let rec = s.record(&AtomicBool::new(false));
        let stats = rec.outcome.unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        (rec.table, stats)
    };
    let (reference, _) = run(FormulationKind::Augmented);
    for f in [FormulationKind::Embedding, FormulationKind::Amalgamated] {
        let (table, stats) = run(f);
        assert!(
            stats.repartitions >= 1,
            "{}: the run must pass its re-partition",
            f.name()
        );
        assert_eq!(table.rows(), reference.rows(), "{}", f.name());
        let mut worst = 0.0f64;
        for c in ["rod1", "rod2", "rod3", "rod4", "rod5"]
            .iter()
            .flat_map(|b| ["x", "y", "z"].map(|k| format!("{b}.{k}")))
        {
            let (a, b) = (reference.column(&c).unwrap(), table.column(&c).unwrap());
            worst = a.iter().zip(&b).fold(worst, |m, (x, y)| m.max((x - y).abs()));
        }
        let (a, b) = (reference.column("energy").unwrap(), table.column("energy").unwrap());
        let energy = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(
            worst < 1e-5,
            "{}: positions {worst:e} m from the augmented run",
            f.name()
        );
        assert!(
            energy < 1e-4,
            "{}: energy {energy:e} J from the augmented run",
            f.name()
        );
    }
}

/// The partition tracker keeps the number of independent equations when it re-partitions: at a
/// state of Bricard's loop moved 1e-4 off its motion (as an integrator's stage may be), the rank
/// found at the tolerance is 30, one more than on the motion; a re-partition there keeps 29
/// equations and the loop's one independent coordinate.
#[test]
fn a_re_partition_keeps_the_degrees_of_freedom() {
    use dalembert::system::{Partition, PartitionTracker};
    let scene = Scene::from_path(root().join("scenes/bricard.toml")).unwrap();
    let model = scene.model.system();
    let sys = model.constraints();
    let mut values = sys.values();
    sys.evaluate(0.0, &scene.q, &scene.qd, &mut values);
    let mut tracker = PartitionTracker::new(1e3);
    let (p, _) = tracker.factor(0.0, sys, &values).unwrap();
    assert_eq!((p.rows.len(), p.independent.len()), (29, 1));
    // Off the motion: every coordinate moved by 1e-4 (positions through the model's own update).
    let mut q = scene.q.clone();
    let off: Vec<f64> = (0..scene.qd.len()).map(|k| 1e-4 * ((k % 7) as f64 - 3.0)).collect();
    model.integrate_positions(&mut q, &off, 1.0);
    sys.evaluate(0.0, &q, &scene.qd, &mut values);
    let fresh = Partition::choose(sys, &values, tracker.rank_tolerance);
    assert_eq!(
        fresh.rows.len(),
        30,
        "the tolerance alone sees full rank off the motion"
    );
    tracker.threshold = 0.0; // any condition is too large: the tracker re-partitions
    let (p, _) = tracker.factor(0.0, sys, &values).unwrap();
    assert_eq!((p.rows.len(), p.independent.len()), (29, 1));
}

/// A partition changes only between steps, and changing it leaves the state as it was. The
/// spatial slider-crank at its (consistent) start, with a named independent coordinate that is
/// regular but not the one full pivoting picks: inside a step ([`PartitionTracker::begin_step`]) a threshold no
/// partition meets changes nothing; the next step's first evaluation re-partitions; and the
/// projection with either partition moves `(q, v)` by round-off only (bar 1e-12: the start is
/// assembled to 1e-12 and the state is of order 1).
#[test]
fn a_partition_changes_only_between_steps_and_keeps_the_state() {
    use dalembert::system::PartitionTracker;
    let scene = Scene::from_path(root().join("scenes/slider-crank-3d.toml")).unwrap();
    let model = scene.model.system();
    let sys = model.constraints();
    let mut values = sys.values();
    sys.evaluate(0.0, &scene.q, &scene.qd, &mut values);
    let picked = PartitionTracker::new(1e3)
        .factor(0.0, sys, &values)
        .unwrap()
        .0
        .independent
        .clone();
    let named = (0..sys.num_coordinates())
        .filter(|&k| vec![k] != picked)
        .find(|&k| {
            let mut t = PartitionTracker::new(1e3).with_independent(sys, vec![k]);
            let kept = t.factor(0.0, sys, &values).is_some_and(|(p, _)| p.independent == [k]);
            kept && t.count() == 0
        })
        .expect("a regular named partition");
    let moved = |tracker: &mut PartitionTracker| {
        let (mut q, mut v, mut values) = (scene.q.clone(), scene.qd.clone(), sys.values());
        tracker.project(0.0, sys, &mut values, &mut q, &mut v, 1e-10).unwrap();
        let dq = q.iter().zip(&scene.q).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        dq.max(v.iter().zip(&scene.qd).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())))
    };
    let mut tracker = PartitionTracker::new(1e3).with_independent(sys, vec![named]);
    tracker.begin_step();
    assert_eq!(tracker.factor(0.0, sys, &values).unwrap().0.independent, [named]);
    tracker.threshold = 0.0; // every partition is now "too ill-conditioned"
    for _ in 0..3 {
        let (p, _) = tracker.factor(0.0, sys, &values).unwrap();
        assert_eq!(p.independent, [named], "a stage re-partitioned");
    }
    assert_eq!(tracker.count(), 0);
    let before = moved(&mut PartitionTracker::new(1e3).with_independent(sys, vec![named]));
    tracker.begin_step();
    let (p, _) = tracker.factor(0.0, sys, &values).unwrap();
    assert_ne!(
        p.independent,
        [named],
        "the step's first evaluation keeps the partition"
    );
    assert_eq!(tracker.count(), 1);
    tracker.threshold = 1e3;
    let after = moved(&mut tracker);
    assert!(
        before < 1e-12 && after < 1e-12,
        "projection moved the state by {before:e} / {after:e}"
    );
}

/// A named partition on redundant equations (Bricard's loop: 30 equations of rank 29, one
/// coordinate named independent) has no square `C_qd`; it is chosen again at the first
/// evaluation with the loop's rank, instead of indexing out of bounds (it panicked until
/// 2026-11-28).
#[test]
fn a_named_partition_on_redundant_equations_is_chosen_again() {
    use dalembert::system::PartitionTracker;
    let scene = Scene::from_path(root().join("scenes/bricard.toml")).unwrap();
    let model = scene.model.system();
    let sys = model.constraints();
    let mut values = sys.values();
    sys.evaluate(0.0, &scene.q, &scene.qd, &mut values);
    let mut tracker = PartitionTracker::new(1e3).with_independent(sys, vec![0]);
    let (p, _) = tracker.factor(0.0, sys, &values).unwrap();
    assert_eq!((p.rows.len(), p.independent.len()), (29, 1));
}

#[test]
fn a_joint_angle_keeps_counting_when_it_turns_more_than_half_a_turn_between_rows() {
    // A wheel spinning freely at 40 rad/s on a revolute joint (no gravity, its centre on the
    // axis: no torque), rows every 0.1 s: 4 rad between rows, more than half a turn. The joint's
    // angle is read within a turn and taken on the turn nearest its last row's value carried on
    // by the rates and accelerations of both rows, so the column is the closed form 40 t
    // (within 1e-9 rad over 2 s, dopri5 1e-11). Taken within half a turn of the last row alone
    // (as before), it ran backwards: 4 rad read as 4 − 2π. The same column from rows every
    // 0.001 s agrees (the row interval does not change it).
    let text = |every: f64| {
        format!(
            "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
             [[bodies]]\nname = \"wheel\"\nmass = 2.0\ninertia = [0.02, 0.02, 0.04]\nposition = [0.0, 0.0, 0.0]\n\
             angular_velocity = [0.0, 0.0, 40.0]\n\
             [[joints]]\nname = \"axle\"\ntype = \"revolute\"\nbodies = [\"ground\", \"wheel\"]\nat = [0.0, 0.0, 0.0]\n\
             axis = [0.0, 0.0, 1.0]\n\
             [simulation]\nend = 2.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = {every}\n"
        )
    };
    for formulation in ["augmented", "embedding", "amalgamated"] {
        let run = |every: f64| {
            let scene = Scene::from_toml(
                &text(every).replace(
                    "[simulation]\n",
                    &format!("[simulation]\nformulation = \"{formulation}\"\n"),
                ),
                "wheel",
            )
            .unwrap();
            let rec = scene.record(&AtomicBool::new(false));
            rec.outcome.unwrap();
            (rec.table.column("t").unwrap(), rec.table.column("axle.q").unwrap())
        };
        let (t, angle) = run(0.1);
        assert_eq!(t.len(), 21);
        for (t, a) in t.iter().zip(&angle) {
            assert!(
                (a - 40.0 * t).abs() < 1e-9,
                "{formulation}: t = {t}: angle {a}, expected {}",
                40.0 * t
            );
        }
        let (t_fine, fine) = run(0.001);
        for (t, a) in t.iter().zip(&angle) {
            let k = t_fine.iter().position(|s| (s - t).abs() < 1e-12).unwrap();
            assert!(
                (fine[k] - a).abs() < 1e-9,
                "{formulation}: t = {t}: {a} against {} from fine rows",
                fine[k]
            );
        }
    }
}
