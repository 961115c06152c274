//! Imported models against the same mechanisms written as scenes (`docs/import.md`): a reader
//! must give the model a scene would, whatever the format. The engines' own checks (Pinocchio,
//! MuJoCo) are the Python tests `test_urdf.py` and `test_mjcf.py`.

use dalembert::output::Table;
use dalembert::{FormulationKind, Scene, SceneValue};
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/imported")
        .join(name)
}

/// 1 s of `scene` with `formulation`, dopri5 at 1e-11, a row every 0.1 s.
fn run(scene: &Scene, formulation: FormulationKind) -> Table {
    let s = scene
        .with_values(&[
            ("simulation.end", 1.0.into()),
            ("simulation.integrator", "dopri5".into()),
            ("simulation.rtol", 1e-11.into()),
            ("simulation.atol", 1e-12.into()),
            ("simulation.output_every", 0.1.into()),
            ("simulation.formulation", SceneValue::Text(formulation.name().into())),
        ])
        .unwrap();
    let rec = s.record(&AtomicBool::new(false));
    rec.outcome
        .unwrap_or_else(|e| panic!("{} {}: {e}", scene.name, formulation.name()));
    rec.table
}

/// The loop of `loop.xml`, closed by an MJCF `equality connect`, moves as `loop.toml`, the same
/// mechanism written as a scene with a spherical joint: every body's centre of mass and Euler
/// parameters within 1e-9 over 1 s (dopri5 at 1e-11 on both: the gap is the integrator's, the
/// models are equal to round-off), with every formulation; and the mechanism moves (its crank
/// turns more than 0.05 rad).
#[test]
fn an_mjcf_connect_loop_moves_as_the_same_loop_written_as_a_scene() {
    let imported = Scene::from_path(data("loop.xml")).unwrap();
    let written = Scene::from_path(data("loop.toml")).unwrap();
    // The same bodies (the reader lists them as it walks the tree: crank, rocker, coupler).
    let (mut a, mut b) = (imported.model.body_names(), written.model.body_names());
    a.sort();
    b.sort();
    assert_eq!(a, b);
    for f in FormulationKind::ALL {
        let (a, b) = (run(&imported, f), run(&written, f));
        assert_eq!(a.rows(), 11);
        for body in imported.model.body_names() {
            for c in ["x", "y", "z", "e0", "e1", "e2", "e3"] {
                let column = format!("{body}.{c}");
                let (x, y) = (a.column(&column).unwrap(), b.column(&column).unwrap());
                let gap = x.iter().zip(&y).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(gap < 1e-9, "{} {column}: {gap:.2e}", f.name());
            }
        }
        let crank = a.column("A.q").unwrap();
        assert!(crank.last().unwrap().abs() > 0.05, "the loop moves: crank at {crank:?}");
    }
}

/// `scenes/robots/ur5-floating.toml`: the UR5 with a floating base, no gravity, two joints
/// started turning. Nothing acts from outside, so the linear momentum `Σ m v` and the angular
/// momentum about the origin `Σ (r × m v + A J Aᵀ ω)` keep their start values over 2 s (dopri5 at
/// 1e-11: 1e-8 of their scale), while the base itself turns (the momenta are shared, not zero in
/// the base); every formulation. In joint coordinates it is refused naming the free base.
#[test]
fn a_floating_base_robot_keeps_its_momenta_and_is_refused_in_joint_coordinates() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/robots/ur5-floating.toml");
    let scene = Scene::from_path(&path).unwrap();
    let model = scene.model.spatial().unwrap();
    let bodies = model.bodies();
    for formulation in FormulationKind::ALL {
        let table = run(&scene, formulation);
        let column = |name: &str| table.column(name).unwrap_or_else(|| panic!("no column {name}"));
        let mut linear = vec![nalgebra::Vector3::zeros(); table.rows()];
        let mut angular = vec![nalgebra::Vector3::zeros(); table.rows()];
        for b in bodies {
            let get = |k: &str| column(&format!("{}.{k}", b.name));
            let (x, y, z) = (get("x"), get("y"), get("z"));
            let (e0, e1, e2, e3) = (get("e0"), get("e1"), get("e2"), get("e3"));
            let (vx, vy, vz) = (get("vx"), get("vy"), get("vz"));
            let (wx, wy, wz) = (get("wx"), get("wy"), get("wz"));
            for i in 0..table.rows() {
                let r = nalgebra::Vector3::new(x[i], y[i], z[i]);
                let v = nalgebra::Vector3::new(vx[i], vy[i], vz[i]);
                let w = nalgebra::Vector3::new(wx[i], wy[i], wz[i]);
                let a = dalembert::spatial::euler_parameters::rotation(&[e0[i], e1[i], e2[i], e3[i]]);
                linear[i] += b.mass * v;
                angular[i] += b.mass * r.cross(&v) + a * b.inertia * a.transpose() * w;
            }
        }
        let scale = angular[0].norm().max(linear[0].norm());
        assert!(scale > 0.1, "{}: momenta {scale}", formulation.name());
        for i in 0..table.rows() {
            assert!(
                (linear[i] - linear[0]).norm() < 1e-8 * scale,
                "{}: row {i}",
                formulation.name()
            );
            assert!(
                (angular[i] - angular[0]).norm() < 1e-8 * scale,
                "{}: row {i}",
                formulation.name()
            );
        }
        let turned = column("world.wz").iter().fold(0.0f64, |m, w| m.max(w.abs()));
        assert!(
            turned > 1e-2,
            "{}: the base does not turn ({turned})",
            formulation.name()
        );
    }
    let joint = scene.with_values(&[("simulation.coordinates", SceneValue::Text("joint".into()))]);
    let message = match joint {
        Err(e) => e.to_string(),
        Ok(s) => s
            .simulation()
            .formulation()
            .map(|_| String::new())
            .unwrap_or_else(|e| e.to_string()),
    };
    assert!(
        message.contains("body 'world': moves freely"),
        "joint coordinates: {message}"
    );
}

/// An MJCF slide with a spring (`stiffness`, `springref`) hanging 3 m below where the file puts
/// it: the spring acts along the slide for any travel (a servo on the slide's displacement), so the
/// body comes to rest at `springref − m g / k` (closed form, 1e-9 m; a spring between two points
/// 1 m apart would have turned around after 1 m of travel), and the linear model there
/// has `A₂₁ = −k/m` and, for the motor of gear 3, `B₂ = gear/m` (1e-9).
#[test]
fn a_sprung_mjcf_slide_rests_where_its_spring_balances_gravity_far_from_the_file() {
    let (m, k, springref, gear) = (2.0, 5.0, 0.5, 3.0);
    let text = format!(
        r#"<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="s" type="slide" axis="0 0 1" stiffness="{k}" springref="{springref}" damping="1"/>
      <geom type="sphere" size="0.1" mass="{m}"/>
    </body>
  </worldbody>
  <actuator><motor name="lift" joint="s" gear="{gear}"/></actuator>
</mujoco>"#
    );
    let path = std::env::temp_dir().join(format!("sprung-slide-{}.xml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let scene = Scene::from_path(&path).unwrap();
    let eq = scene.equilibrium().unwrap();
    let z = eq.positions.iter().find(|(n, _)| n == "a.z").unwrap().1;
    let expected = 1.0 + springref - m * 9.81 / k;
    assert!(expected < -2.0, "the rest is far below the file's position");
    assert!((z - expected).abs() < 1e-9, "z = {z}, expected {expected}");
    let lin = scene
        .linearize(&dalembert::LinearizeOptions {
            inputs: vec!["lift".into()],
            states: vec!["a.z".into()],
            ..Default::default()
        })
        .unwrap();
    assert!((lin.b[(1, 0)] - gear / m).abs() < 1e-9, "B = {}", lin.b);
    assert!((lin.a[(1, 0)] + k / m).abs() < 1e-9, "A = {}", lin.a);
    std::fs::remove_file(&path).ok();
}

/// The rod of [`imported_rod`] as a URDF: its joint of `kind` about −y, with `extra` in it.
fn rod_urdf(kind: &str, extra: &str) -> String {
    format!(
        r#"<robot name="rod">
  <link name="world"/>
  <link name="rod">
    <inertial><origin xyz="0.5 0 0"/><mass value="1"/>
      <inertia ixx="0.001" iyy="0.08333333333333333" izz="0.08333333333333333" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="pin" type="{kind}">
    <parent link="world"/><child link="rod"/><axis xyz="0 -1 0"/>
    {extra}
  </joint>
</robot>"#
    )
}

/// The same rod as an MJCF: its hinge about −y with the attributes `extra`.
fn rod_mjcf(extra: &str) -> String {
    format!(
        r#"<mujoco>
  <worldbody>
    <body name="rod">
      <joint name="pin" type="hinge" axis="0 -1 0" {extra}/>
      <inertial pos="0.5 0 0" mass="1" diaginertia="0.001 0.08333333333333333 0.08333333333333333"/>
    </body>
  </worldbody>
</mujoco>"#
    )
}

/// A uniform rod of 1 kg and 1 m pinned at one end, released horizontal, in `file` (a URDF or an
/// MJCF text) written to a temporary file named `name`.
fn imported_rod(name: &str, file: &str) -> dalembert::output::Table {
    imported_rod_in(name, file, dalembert::Coordinates::Absolute)
}

/// [`imported_rod`] integrated in `coordinates`.
fn imported_rod_in(name: &str, file: &str, coordinates: dalembert::Coordinates) -> dalembert::output::Table {
    let path = std::env::temp_dir().join(format!("{}-{name}", std::process::id()));
    std::fs::write(&path, file).unwrap();
    let mut scene = Scene::from_path(&path).unwrap();
    std::fs::remove_file(&path).ok();
    scene.settings.coordinates = coordinates;
    scene.settings.end = 1.5;
    scene.settings.method = dalembert::integrators::Method::dopri5(1e-11, 1e-11);
    let rec = scene.record(&std::sync::atomic::AtomicBool::new(false));
    rec.outcome.unwrap();
    rec.table
}

#[test]
fn urdf_limits_and_mjcf_ranges_are_stops() {
    // The rod falls from horizontal onto a stop 1 rad below it (a URDF `<limit lower="-1">`,
    // an MJCF `range` in degrees) and rests there: a plastic stop takes all the kinetic energy,
    // so it ends at rest with E = m g (L/2) sin(−1) (datum at the pin), held by the stop's torque
    // m g (L/2) cos 1 = 2.650 N·m against its weight. dopri5 at 1e-11: the angle within 1e-9
    // rad of the stop, the energy within 1e-8 J and the torque within 1e-8 N·m of these.
    let urdf = rod_urdf(
        "revolute",
        r#"<limit lower="-1" upper="0.5" effort="10" velocity="10"/>"#,
    );
    let mjcf = rod_mjcf(r#"range="-57.29577951308232 28.64788975654116""#);
    let (m, g, half) = (1.0, 9.81, 0.5);
    for (name, file) in [("rod.urdf", urdf), ("rod.xml", mjcf)] {
        let table = imported_rod(name, &file);
        let last = |c: &str| *table.column(c).unwrap().last().unwrap();
        let angle = last("pin.q");
        assert!((angle + 1.0).abs() < 1e-9, "{name}: rests at {angle} rad, expected -1");
        let energy = last("energy");
        let expected = m * g * half * (-1.0f64).sin();
        assert!(
            (energy - expected).abs() < 1e-8,
            "{name}: E = {energy}, expected {expected}"
        );
        let torque = last("pin.limit").abs();
        let expected = m * g * half * 1.0f64.cos();
        assert!(
            (torque - expected).abs() < 1e-8,
            "{name}: held by {torque} N·m, expected {expected}"
        );
    }
}

#[test]
fn urdf_and_mjcf_joint_friction_is_a_constant_friction_torque() {
    // The rod released horizontal pulls on its pin with m g L/2 = 4.905 N·m. A URDF
    // `<dynamics friction>` or an MJCF `frictionloss` of 5 N·m holds it there exactly (the
    // angle stays 0 within 1e-12 rad, the friction column is the weight's torque within 1e-9
    // N·m); one of 4 N·m lets it fall, and at 1.5 s its energy has fallen by the friction's
    // work, 4 N·m times the angle it turned through (the balance E − W, dopri5 at 1e-11: 1e-8 J).
    // In absolute and in joint coordinates alike.
    let (m, g, half) = (1.0, 9.81, 0.5);
    for (f0, coordinates) in [5.0, 4.0].into_iter().flat_map(|f0| {
        [
            (f0, dalembert::Coordinates::Absolute),
            (f0, dalembert::Coordinates::Joint),
        ]
    }) {
        let urdf = rod_urdf("continuous", &format!(r#"<dynamics friction="{f0}"/>"#));
        let mjcf = rod_mjcf(&format!(r#"frictionloss="{f0}""#));
        for (file_name, file) in [("rod-friction.urdf", urdf), ("rod-friction.xml", mjcf)] {
            let table = imported_rod_in(file_name, &file, coordinates);
            let name = format!("{file_name} in {coordinates:?} coordinates");
            let angle = table.column("pin.q").unwrap();
            let friction = table.column("pin.friction").unwrap();
            let energy = table.column("energy").unwrap();
            if f0 > m * g * half {
                let moved = angle.iter().fold(0.0f64, |a, q| a.max(q.abs()));
                assert!(moved < 1e-12, "{name}: held by {f0} N·m, moved {moved} rad");
                let held = friction.last().unwrap().abs();
                assert!((held - m * g * half).abs() < 1e-9, "{name}: friction {held} N·m");
            } else {
                let turned = angle.last().unwrap().abs();
                assert!(
                    turned > 0.1,
                    "{name}: with {f0} N·m the rod should fall, turned {turned} rad"
                );
                // The friction opposes the motion throughout the first swing down: W = −f₀ |Δθ|
                // while the rod turns one way (it has not come back by 1.5 s: checked by the
                // angle's monotony).
                assert!(
                    angle.windows(2).all(|w| w[1] <= w[0] + 1e-15),
                    "{name}: the rod turned back"
                );
                let balance = energy.last().unwrap() - energy[0] + f0 * turned;
                assert!(balance.abs() < 1e-8, "{name}: E − W drifts {balance:e} J");
            }
        }
    }
}
