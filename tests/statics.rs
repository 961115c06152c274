//! Static equilibrium and vibration modes against closed forms: a compound pendulum
//! (`ω² = m g d / J_O`), a double pendulum of point masses (`ω² = (g/L)(2 ∓ √2)`, shapes
//! `x₂/x₁ = 1 ± √2`), a mass–spring–damper (`x = −m g / k`, `ω_n = √(k/m)`,
//! `ζ = c / (2√(k m))`), a slider-crank held by a driver against a piston force
//! (`T = −F ∂x/∂θ`, virtual work), a spherical pendulum (both swings, a free spin); variants
//! written another way (bodies listed in reverse, a perturbed start) give the same answers; and
//! what has no equilibrium is refused naming the free direction.

use dalembert::{EquilibriumError, Scene};

/// Value of column `name` in a list of named values.
fn named(list: &[(String, f64)], name: &str) -> f64 {
    list.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no column {name} in {list:?}"))
        .1
}

const G: f64 = 9.81;

#[test]
fn a_compound_pendulum_hangs_and_swings_at_its_closed_form() {
    // The shipped pendulum (uniform rod, 1 kg, 1 m, pinned at one end) released 60° from the
    // vertical: it comes to rest hanging, its centre of mass below the pivot at the distance the
    // file gives (d = |(0.25, −0.433)| = 0.49999, the file's rounding), Newton to the assembly's
    // 1e-12; the pivot carries its weight; it swings at ω² = m g d / (m L²/12 + m d²)
    // (relative 1e-10: a 1 × 1 eigenproblem of exact matrices).
    let scene = Scene::from_path("scenes/pendulum.toml").unwrap();
    let d = (0.25f64 * 0.25 + 0.433 * 0.433).sqrt();
    let eq = scene.equilibrium().unwrap();
    assert!((named(&eq.positions, "rod.x")).abs() < 1e-12, "{:?}", eq.positions);
    assert!((named(&eq.positions, "rod.y") + d).abs() < 1e-12, "{:?}", eq.positions);
    assert!(eq.stable && eq.stiffness.len() == 1 && eq.free_directions.is_empty());
    // The reaction on the ground from the rod: its weight, downward.
    assert!(
        (named(&eq.reactions, "pivot.fy") + G).abs() < 1e-10,
        "{:?}",
        eq.reactions
    );
    assert!(named(&eq.reactions, "pivot.fx").abs() < 1e-10, "{:?}", eq.reactions);
    let modes = scene.modes().unwrap();
    let expected = (G * d / (1.0 / 12.0 + d * d)).sqrt() / (2.0 * std::f64::consts::PI);
    assert_eq!(modes.frequencies.len(), 1);
    assert!(
        (modes.frequencies[0] - expected).abs() < 1e-10 * expected,
        "{} Hz, expected {expected}",
        modes.frequencies[0]
    );
    assert_eq!(modes.damping_ratios, [0.0]);
}

/// Two point masses `m` on massless links of length 1 hanging from the ground, each given a
/// tiny inertia 1e-12 kg·m² about its centre (a planar body has one; it changes the frequencies
/// by 1e-12 relative). `reversed` lists the bodies and joints in the other order.
fn double_pendulum(reversed: bool, start_angle: f64) -> Scene {
    let (s, c) = start_angle.sin_cos();
    let upper = format!(
        "[[bodies]]\nname = \"upper\"\nmass = 1.0\ninertia = 1e-12\nposition = [{}, {}]\nangle = {start_angle}\n",
        s, -c
    );
    let lower = format!(
        "[[bodies]]\nname = \"lower\"\nmass = 1.0\ninertia = 1e-12\nposition = [{}, {}]\nangle = {start_angle}\n",
        2.0 * s,
        -2.0 * c
    );
    let shoulder =
        "[[joints]]\nname = \"shoulder\"\ntype = \"revolute\"\nbodies = [\"ground\", \"upper\"]\nat = [0.0, 0.0]\n";
    let elbow = format!(
        "[[joints]]\nname = \"elbow\"\ntype = \"revolute\"\nbodies = [\"upper\", \"lower\"]\nat = [{s}, {}]\n",
        -c
    );
    let parts = if reversed {
        [lower, upper, elbow, shoulder.to_string()]
    } else {
        [upper, lower, shoulder.to_string(), elbow]
    };
    let text = format!("[scene]\ngravity = [0.0, -9.81]\n{}", parts.join("\n"));
    Scene::from_toml(&text, "double pendulum").unwrap()
}

#[test]
fn a_double_pendulum_of_point_masses_has_its_two_closed_form_modes() {
    // ω² = (g/L)(2 ∓ √2) and amplitude ratios x_lower / x_upper = 1 ± √2 (the links' angles in
    // ratio ±√2). Written both ways and started 0.4 rad off: the same equilibrium (hanging) and
    // modes. Tolerances: frequencies 1e-9 relative (the 1e-12 inertias and a 2 × 2 eigenproblem),
    // shape ratios 1e-9.
    let sqrt2 = 2.0f64.sqrt();
    let expected = [
        (G * (2.0 - sqrt2)).sqrt() / (2.0 * std::f64::consts::PI),
        (G * (2.0 + sqrt2)).sqrt() / (2.0 * std::f64::consts::PI),
    ];
    for (reversed, start) in [(false, 0.0), (true, 0.0), (false, 0.4), (true, -0.3)] {
        let scene = double_pendulum(reversed, start);
        let modes = scene.modes().unwrap();
        let eq = &modes.equilibrium;
        assert!(eq.stable);
        assert!(
            (named(&eq.positions, "lower.y") + 2.0).abs() < 1e-12,
            "{:?}",
            eq.positions
        );
        assert!(named(&eq.positions, "lower.x").abs() < 1e-12, "{:?}", eq.positions);
        for (k, f) in expected.iter().enumerate() {
            let got = modes.frequencies[k];
            assert!(
                (got - f).abs() < 1e-9 * f,
                "reversed {reversed}, start {start}: mode {k} at {got} Hz, expected {f}"
            );
        }
        let column = |name: &str| modes.columns.iter().position(|c| c == name).unwrap();
        let (xu, xl) = (column("upper.x"), column("lower.x"));
        for (k, ratio) in [1.0 + sqrt2, 1.0 - sqrt2].iter().enumerate() {
            let shape = &modes.shapes[k];
            let got = shape[xl] / shape[xu];
            assert!((got - ratio).abs() < 1e-9, "mode {k}: x ratio {got}, expected {ratio}");
        }
    }
}

#[test]
fn a_mass_on_a_spring_rests_at_its_static_deflection_and_rings_at_its_frequency() {
    // y = −1 − m g / k; ω_n = √(k/m), ζ = c / (2√(k m)) (the single pair of eigenvalues of the
    // first-order system: 1e-10 relative).
    // tests/data/hanging-spring.toml: m = 2 kg, k = 400 N/m, c = 4 N·s/m.
    let (m, k, c) = (2.0, 400.0, 4.0);
    let scene = Scene::from_path("tests/data/hanging-spring.toml").unwrap();
    let eq = scene.equilibrium().unwrap();
    let y = named(&eq.positions, "slider.y");
    assert!((y - (-1.0 - m * G / k)).abs() < 1e-12, "y = {y}");
    assert!(eq.stable);
    // The guide carries no force along its axis, and nothing across it.
    assert!(named(&eq.reactions, "guide.fx").abs() < 1e-10, "{:?}", eq.reactions);
    let modes = scene.modes().unwrap();
    let (wn, zeta) = ((k / m).sqrt(), c / (2.0 * (k * m).sqrt()));
    let f = wn / (2.0 * std::f64::consts::PI);
    assert!((modes.frequencies[0] - f).abs() < 1e-10 * f, "{:?}", modes.frequencies);
    assert!(
        (modes.damping_ratios[0] - zeta).abs() < 1e-10,
        "{:?}",
        modes.damping_ratios
    );
}

#[test]
fn a_slider_crank_held_by_its_driver_balances_the_piston_force_by_virtual_work() {
    // Crank r = 0.1 at 50°, rod l = 0.3, a piston force F = 200 N along −x on the slider, no
    // gravity; a driver holds the crank's angle. By virtual work the driver's torque is
    // T = −F ∂x/∂θ with x = r cos θ + √(l² − r² sin² θ): the driver's effort equals it to 1e-9
    // relative (the multipliers of an exact solve).
    let (r, l, theta, force) = (0.1f64, 0.3f64, 50f64.to_radians(), 200.0);
    let (s, c) = theta.sin_cos();
    let pin = [r * c, r * s];
    let x = r * c + (l * l - r * r * s * s).sqrt();
    let rod_angle = (-pin[1]).atan2(x - pin[0]);
    let text = format!(
        r#"
[scene]
gravity = [0.0, 0.0]
[[bodies]]
name = "crank"
mass = 1.0
inertia = 0.01
position = [{cx}, {cy}]
angle = {theta}
[[bodies]]
name = "rod"
mass = 1.0
inertia = 0.01
position = [{rx}, {ry}]
angle = {rod_angle}
[[bodies]]
name = "piston"
mass = 1.0
inertia = 0.01
position = [{x}, 0.0]
[[joints]]
name = "A"
type = "revolute"
bodies = ["ground", "crank"]
at = [0.0, 0.0]
[[joints]]
name = "B"
type = "revolute"
bodies = ["crank", "rod"]
at = [{px}, {py}]
[[joints]]
name = "C"
type = "revolute"
bodies = ["rod", "piston"]
at = [{x}, 0.0]
[[joints]]
name = "guide"
type = "prismatic"
bodies = ["ground", "piston"]
at = [{x}, 0.0]
axis = [1.0, 0.0]
[[drivers]]
name = "hold"
type = "joint-angle"
joint = "A"
function = {{ kind = "linear", rate = 0.0 }}
[[forces]]
name = "gas"
type = "force"
body = "piston"
value = [{gas:.1}, 0.0]
"#,
        cx = pin[0] / 2.0,
        cy = pin[1] / 2.0,
        rx = (pin[0] + x) / 2.0,
        ry = pin[1] / 2.0,
        px = pin[0],
        py = pin[1],
        gas = -force,
    );
    let scene = Scene::from_toml(&text, "held slider-crank").unwrap();
    let eq = scene.equilibrium().unwrap();
    let dx_dtheta = -r * s - r * r * s * c / (l * l - r * r * s * s).sqrt();
    let torque = -(-force) * dx_dtheta;
    let effort = named(&eq.reactions, "hold.effort");
    assert!(
        (effort.abs() - torque.abs()).abs() < 1e-9 * torque.abs(),
        "effort {effort}, virtual work {torque}"
    );
    assert!(eq.stiffness.is_empty(), "a fully driven mechanism has no free motion");
}

#[test]
fn a_spherical_pendulum_swings_about_both_axes_and_spins_freely() {
    // A body of 3 kg hanging d = 0.8 m below a spherical joint, principal moments 0.05 and 0.07
    // about its horizontal x and y axes: ω² = m g d / (J + m d²) about each (1e-10 relative); the
    // spin about the vertical has no stiffness: a neutral direction named with the equilibrium,
    // a mode of 0 Hz.
    let text = r#"
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
"#;
    let scene = Scene::from_toml(text, "spherical pendulum").unwrap();
    let modes = scene.modes().unwrap();
    let eq = &modes.equilibrium;
    assert!(!eq.stable, "a free spin is not a stable equilibrium");
    assert_eq!(eq.free_directions.len(), 1, "{:?}", eq.free_directions);
    assert!(eq.free_directions[0].contains("bob.wz"), "{:?}", eq.free_directions);
    let (m, d) = (3.0, 0.8);
    let f = |j: f64| (m * G * d / (j + m * d * d)).sqrt() / (2.0 * std::f64::consts::PI);
    assert!(modes.frequencies[0].abs() < 1e-6, "{:?}", modes.frequencies);
    for (k, j) in [(1, 0.07), (2, 0.05)] {
        let got = modes.frequencies[k];
        assert!(
            (got - f(j)).abs() < 1e-10 * f(j),
            "mode {k}: {got} Hz, expected {}",
            f(j)
        );
    }
    assert!((named(&eq.positions, "bob.z") + d).abs() < 1e-12, "{:?}", eq.positions);
}

#[test]
fn a_free_body_under_gravity_has_no_equilibrium_and_says_so() {
    let text = r#"
[scene]
gravity = [0.0, -9.81]
[[bodies]]
name = "stone"
mass = 2.0
inertia = 0.1
position = [0.0, 1.0]
"#;
    let scene = Scene::from_toml(text, "falling stone").unwrap();
    let e = scene.equilibrium().unwrap_err();
    assert!(
        matches!(e, EquilibriumError::Mechanism { force, .. } if (force - 2.0 * G).abs() < 1e-9),
        "{e:?}"
    );
    let text = e.to_string();
    assert!(text.contains("stone.y"), "{text}");
    assert!(text.contains("there is none: a net force of 19.62"), "{text}");
    assert!(!text.contains('\n'));
}

#[test]
fn scenes_started_far_from_rest_settle_where_their_motion_comes_to_rest() {
    // The shipped double pendulum starts horizontal: Newton's method from there ends at an
    // unstable equilibrium, and the motion with kinetic damping brings it to the hanging one.
    // Two uniform rods (m = L = 1) in absolute angles: M = m L² [4/3 1/2; 1/2 1/3],
    // K = m g L diag(3/2, 1/2), so ω² = g (3 ∓ √1008 / 14) (1e-9 relative).
    let scene = Scene::from_path("scenes/double-pendulum.toml").unwrap();
    let modes = scene.modes().unwrap();
    assert!(modes.equilibrium.stable);
    assert!((named(&modes.equilibrium.positions, "lower.y") + 1.5).abs() < 1e-12);
    for (k, sign) in [(0, -1.0), (1, 1.0)] {
        let w2 = G * (3.0 + sign * 1008f64.sqrt() / 14.0);
        let f = w2.sqrt() / (2.0 * std::f64::consts::PI);
        let got = modes.frequencies[k];
        assert!((got - f).abs() < 1e-9 * f, "mode {k}: {got} Hz, expected {f}");
    }
    // The shipped heavy top lies horizontal (its centre 1 m from the ball joint, 15 kg, moments
    // 0.234375 about the horizontal axes): it comes to hang, neutral about its symmetry axis, and
    // swings at ω² = m g d / (J + m d²) about both horizontal axes (1e-10 relative).
    let scene = Scene::from_path("scenes/heavy-top.toml").unwrap();
    let modes = scene.modes().unwrap();
    let eq = &modes.equilibrium;
    assert!(
        (named(&eq.positions, "top.z") + 1.0).abs() < 1e-12,
        "{:?}",
        eq.positions
    );
    assert_eq!(eq.free_directions.len(), 1, "{:?}", eq.free_directions);
    let f = (15.0 * G / (0.234375 + 15.0)).sqrt() / (2.0 * std::f64::consts::PI);
    assert!(modes.frequencies[0].abs() < 1e-6, "{:?}", modes.frequencies);
    for k in [1, 2] {
        assert!(
            (modes.frequencies[k] - f).abs() < 1e-10 * f,
            "{:?}, expected {f}",
            modes.frequencies
        );
    }
}

/// A spatial chain of eight 1 m links (`chain3d_toml`: revolute joints about alternating axes)
/// released in a horizontal line relaxes in joint coordinates (the articulated-body algorithm)
/// and comes to hang straight down from its first joint: link `i`'s centre at `(0, 0, −(i + ½))`
/// (1e-9 m, the potential's only minimum), stable, with no free direction. Written with its links
/// listed in reverse, the same.
#[test]
fn a_spatial_chain_released_horizontal_comes_to_hang_straight_down() {
    let text = dalembert_testkit::spatial::chain3d_toml(8, 1.0);
    // The same chain with its bodies listed last link first.
    let blocks: Vec<&str> = text.split("\n[[").collect();
    let (head, rest) = blocks.split_first().unwrap();
    let (bodies, others): (Vec<&str>, Vec<&str>) = rest.iter().partition(|b| b.starts_with("bodies]]"));
    let reversed = std::iter::once(head.to_string())
        .chain(bodies.iter().rev().chain(&others).map(|b| format!("[[{b}")))
        .collect::<Vec<_>>()
        .join("\n");
    assert_eq!(bodies.len(), 8);
    for (what, text) in [("as written", text.clone()), ("bodies reversed", reversed)] {
        let scene = Scene::from_toml(&text, "chain").unwrap();
        let eq = scene.equilibrium().unwrap();
        assert!(
            eq.stable && eq.free_directions.is_empty(),
            "{what}: {:?}",
            eq.unstable_directions
        );
        for i in 0..8 {
            let at = |k: &str| named(&eq.positions, &format!("link{i}.{k}"));
            let expected = [0.0, 0.0, -(i as f64 + 0.5)];
            for (k, e) in ["x", "y", "z"].iter().zip(expected) {
                assert!(
                    (at(k) - e).abs() < 1e-9,
                    "{what}: link{i}.{k} = {} (expected {e})",
                    at(k)
                );
            }
        }
    }
}

/// A spatial double pendulum of two boxes (1 kg, 1 m × 0.1 m × 0.1 m along x, revolute joints
/// about y at x = 0 and x = 1) released horizontal comes to hang and swings at the closed form of
/// two compound pendulums: absolute angles about the hanging position, `J = m (L² + c²)/12` about
/// y, `M = [J + 5/4, 1/2; 1/2, J + 1/4]`, `K = g diag(3/2, 1/2)`, `ω²` the roots of
/// `det(K − ω² M) = 0` (1e-9 relative). The start lies on a maximum of the second link's potential
/// along its own joint and nowhere near the well (the descent in joint coordinates goes down its
/// negative curvature, `docs/statics.md`, "Far from rest"); the same with the bodies and joints
/// listed in reverse, and with the start moved by 1e-12 rad.
#[test]
fn a_spatial_double_pendulum_released_horizontal_swings_at_its_closed_form() {
    let body = |name: &str, x: f64| {
        format!("[[bodies]]\nname = \"{name}\"\nmass = 1.0\nshape = {{ box = [1.0, 0.1, 0.1] }}\nposition = [{x:?}, 0.0, 0.0]\n")
    };
    let joint = |name: &str, a: &str, b: &str, x: f64| {
        format!("[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\nat = [{x:?}, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n")
    };
    let head = "[scene]\ngravity = [0.0, 0.0, -9.81]\n";
    let parts = [
        body("upper", 0.5),
        body("lower", 1.5),
        joint("shoulder", "ground", "upper", 0.0),
        joint("elbow", "upper", "lower", 1.0),
    ];
    let written = format!("{head}{}", parts.join(""));
    let reversed = format!("{head}{}{}{}{}", parts[1], parts[0], parts[3], parts[2]);
    let moved = format!("{written}[initial]\njoints = {{ shoulder = 1e-12 }}\n");
    let j = (1.0 + 0.01) / 12.0;
    let (m11, m12, m22, k11, k22) = (j + 1.25, 0.5, j + 0.25, 1.5 * G, 0.5 * G);
    let (a, b, c) = (m11 * m22 - m12 * m12, -(k11 * m22 + k22 * m11), k11 * k22);
    let root = (b * b - 4.0 * a * c).sqrt();
    let expected = [(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)];
    for (what, text) in [
        ("as written", written),
        ("listed in reverse", reversed),
        ("moved 1e-12", moved),
    ] {
        let modes = Scene::from_toml(&text, "double pendulum").unwrap().modes().unwrap();
        let eq = &modes.equilibrium;
        assert!(eq.stable, "{what}: {:?}", eq.unstable_directions);
        assert!(
            (named(&eq.positions, "lower.z") + 1.5).abs() < 1e-9,
            "{what}: {:?}",
            eq.positions
        );
        assert!(
            named(&eq.positions, "lower.x").abs() < 1e-9,
            "{what}: {:?}",
            eq.positions
        );
        for (k, w2) in expected.iter().enumerate() {
            let f = w2.sqrt() / (2.0 * std::f64::consts::PI);
            let got = modes.frequencies[k];
            assert!((got - f).abs() < 1e-9 * f, "{what}: mode {k}: {got} Hz, expected {f}");
        }
    }
}

#[test]
fn a_parallelogram_with_a_redundant_crank_balances_and_swings_at_its_closed_form() {
    // The shipped parallelogram (three 1 kg cranks of 1 m pinned at their top ends, a 2 kg coupler
    // translating; one crank redundant): it hangs with every crank vertical; T = ½ (3 m L²/3 +
    // m_c L²) θ̇², V = (3 m L/2 + m_c L) g (1 − cos θ), so ω² = 3.5 g / 3 (1e-10 relative). The
    // multipliers are the minimum-norm ones, as in a run: by symmetry each crank's pin carries its
    // own weight and a third of the coupler's, 9.81 + 6.54 N (1e-9).
    let scene = Scene::from_path("scenes/redundant-parallelogram.toml").unwrap();
    let modes = scene.modes().unwrap();
    let eq = &modes.equilibrium;
    assert!(eq.stable);
    let f = (3.5 * G / 3.0).sqrt() / (2.0 * std::f64::consts::PI);
    assert!(
        (modes.frequencies[0] - f).abs() < 1e-10 * f,
        "{:?}, expected {f}",
        modes.frequencies
    );
    for pin in ["A", "E", "D"] {
        let fy = named(&eq.reactions, &format!("{pin}.fy"));
        assert!((fy + G + 2.0 * G / 3.0).abs() < 1e-9, "{pin}.fy = {fy}");
    }
}

#[test]
fn a_mode_is_drawn_as_its_shape_swinging_at_its_frequency_with_the_joints_kept() {
    // The shipped pendulum's one mode: frames over 2 periods of the closed-form frequency
    // (48 per period). The rod stays on its pivot (centre d from it, 1e-12: each frame is
    // assembled); it is at the equilibrium at every half period and farthest from it at a
    // quarter, turned by the amplitude's rule (no centre moved by more than a tenth of the
    // model's size, no body turned by more than 0.3 rad: here the centre's 0.1 × d binds).
    let scene = Scene::from_path("scenes/pendulum.toml").unwrap();
    let modes = scene.modes().unwrap();
    let frames = scene.mode_frames(&modes, 0, 2).unwrap();
    let d = (0.25f64 * 0.25 + 0.433 * 0.433).sqrt();
    let f = (G * d / (1.0 / 12.0 + d * d)).sqrt() / (2.0 * std::f64::consts::PI);
    assert_eq!(frames.len(), 97);
    assert!((frames.times[96] - 2.0 / f).abs() < 1e-12 * (2.0 / f));
    let theta_eq = modes.equilibrium.q[2];
    let pose = |k: usize| &frames.poses[3 * k..3 * k + 3];
    for k in 0..frames.len() {
        let p = pose(k);
        assert!((p[0].hypot(p[1]) - d).abs() < 1e-12, "frame {k}: {p:?}");
    }
    for k in [0, 24, 48, 72, 96] {
        assert!(
            (pose(k)[2] - theta_eq).abs() < 1e-12,
            "frame {k} at rest: {:?}",
            pose(k)
        );
    }
    let swing = (pose(12)[2] - theta_eq).abs();
    // The linear step along the shape moves the centre by 0.1 × d (the model's largest
    // translational coordinate) across, turning the rod by 0.1 rad; the assembly's least change
    // then takes back a second-order part, at most (0.1)²/2 of it (5e-4 rad).
    assert!((swing - 0.1).abs() < 5e-4, "swing {swing}");
    assert!(
        (pose(36)[2] - theta_eq + swing).abs() < 1e-12,
        "three quarters: {:?}",
        pose(36)
    );
    // Asking for a mode the scene does not have names the count.
    let e = scene.mode_frames(&modes, 3, 1).unwrap_err().to_string();
    assert!(e.contains("mode 4 asked for: the scene has 1 mode(s)"), "{e}");
}

#[test]
fn a_scene_written_at_its_equilibrium_starts_there_at_rest_and_stays() {
    // The shipped double pendulum (planar) and heavy top (spatial, spinning, on a spherical
    // joint) started far from rest: `resting_at` gives the scene with `[initial]` positions at the
    // equilibrium and zero velocities. Read again it starts at the equilibrium (1e-12: the
    // positions as written, assembled) with every velocity 0 (exact), its own equilibrium is
    // found where it starts (at most one polishing Newton step), and its motion from there stays
    // there: over 2 s nothing moves by more than 1e-9 (a stable equilibrium; the run's rounding).
    for path in ["scenes/double-pendulum.toml", "scenes/heavy-top.toml"] {
        let scene = Scene::from_path(path).unwrap();
        let eq = scene.equilibrium().unwrap();
        let resting = scene.resting_at(&eq).unwrap();
        assert!(resting.source.contains("[initial.positions]"), "{path}");
        for (a, b) in resting.q.iter().zip(&eq.q) {
            assert!((a - b).abs() < 1e-12, "{path}: {:?} against {:?}", resting.q, eq.q);
        }
        assert!(resting.qd.iter().all(|&v| v == 0.0), "{path}: {:?}", resting.qd);
        let again = resting.equilibrium().unwrap();
        assert!(again.iterations <= 1, "{path}: {} iterations", again.iterations);
        let mut sim = resting.simulator().unwrap();
        let mut moved = 0.0f64;
        for k in 1..=20 {
            sim.advance_to(0.1 * k as f64).unwrap();
            let (q, _) = sim.state();
            moved = q.iter().zip(&eq.q).fold(moved, |m, (a, b)| m.max((a - b).abs()));
        }
        assert!(moved < 1e-9, "{path}: moved {moved}");
    }
}
