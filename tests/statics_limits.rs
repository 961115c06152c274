//! Equilibria against joint limits (`docs/statics.md`, "Joint limits"), against closed forms: a
//! rod resting on a stop of its pin (the stop's torque `m g (L/2) cos θ_b`, the pin carrying the
//! weight), at either bound; a slider resting against the foot of its incline (the stop's force
//! `m g sin α`, the guide's `m g cos α`), reached only by the motion (the model without its
//! stops has no equilibrium); and a double pendulum whose upper rod rests on a stop while the
//! lower one hangs from it and swings at the compound pendulum's `ω² = 3 g / (2 L)`.

use dalembert::Scene;

const G: f64 = 9.81;

fn named(list: &[(String, f64)], name: &str) -> f64 {
    list.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no column {name} in {list:?}"))
        .1
}

/// Asserts that column `name` of `list` is `want` within `tolerance`.
fn assert_near(list: &[(String, f64)], name: &str, want: f64, tolerance: f64) {
    let got = named(list, name);
    assert!(
        (got - want).abs() < tolerance,
        "{name} = {got}, expected {want}: {list:?}"
    );
}

/// A uniform rod (1 kg, 1 m) pinned at its end at the origin, lying along `direction` (±1: along
/// ±x), with stops `[-0.5, 0.5]` rad from there; `points` places the pin by local points instead
/// of a global one.
fn rod_on_a_stop(direction: f64, points: bool) -> Scene {
    let angle = if direction > 0.0 { 0.0 } else { std::f64::consts::PI };
    let place = if points {
        "points = [[0.0, 0.0], [-0.5, 0.0]]".to_string()
    } else {
        "at = [0.0, 0.0]".to_string()
    };
    let toml = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\n[[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\n\
         position = [{}, 0.0]\nangle = {angle}\n\n[[joints]]\nname = \"pin\"\ntype = \"revolute\"\n\
         bodies = [\"ground\", \"rod\"]\n{place}\nlimits = [-0.5, 0.5]\n",
        0.5 * direction
    );
    Scene::from_toml(&toml, "rod").unwrap()
}

#[test]
fn a_rod_rests_on_the_stop_of_its_pin_with_the_torque_its_weight_needs() {
    // Hanging straight down lies 1.57 rad past the stops: the rod rests on the lower one (lying
    // along +x, it turns down, −) or the upper one (along −x, +). Balance about the pin: the stop
    // carries the weight's torque, ∓ m g (L/2) cos 0.5; the pin the weight. The coordinate at the
    // bound to Newton's 1e-12, the forces to 1e-10 of the weight (the residual's tolerance).
    let torque = G * 0.5 * 0.5f64.cos();
    for (direction, bound, push) in [(1.0, -0.5, 1.0), (-1.0, 0.5, -1.0)] {
        for points in [false, true] {
            let eq = rod_on_a_stop(direction, points).equilibrium().unwrap();
            let what = format!("direction {direction}, points {points}");
            assert_eq!(eq.held, ["pin"], "{what}");
            assert!(
                (named(&eq.reactions, "pin.q") - bound).abs() < 1e-12,
                "{what}: {:?}",
                eq.reactions
            );
            assert!(
                (named(&eq.reactions, "pin.limit") - push * torque).abs() < 1e-10 * G,
                "{what}: {:?}",
                eq.reactions
            );
            assert!(named(&eq.reactions, "pin.fx").abs() < 1e-10 * G, "{what}");
            assert!((named(&eq.reactions, "pin.fy").abs() - G).abs() < 1e-10 * G, "{what}");
            // Held, the rod has no motion left: stable, no mode.
            assert!(eq.stable && eq.stiffness.is_empty(), "{what}");
        }
    }
}

#[test]
fn a_slider_rests_against_the_stop_at_the_foot_of_its_incline() {
    // A 2 kg slider on a guide rising at 30°, its stops 0.2 m below and 0.3 m above its start:
    // without them nothing holds it (Newton's method finds no equilibrium), its motion slides it
    // onto the lower stop, which carries m g sin α along the guide; the guide's reaction and the
    // stop's force together carry the weight. Same tolerances as above.
    let (s, c) = (0.5, 0.75f64.sqrt());
    let toml = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\n[[bodies]]\nname = \"slider\"\nmass = 2.0\ninertia = 0.1\n\
         position = [0.0, 0.0]\n\n[[joints]]\nname = \"guide\"\ntype = \"prismatic\"\n\
         bodies = [\"ground\", \"slider\"]\nat = [0.0, 0.0]\naxis = [{c}, {s}]\nlimits = [-0.2, 0.3]\n"
    );
    let eq = Scene::from_toml(&toml, "incline").unwrap().equilibrium().unwrap();
    assert_eq!(eq.held, ["guide"]);
    assert_near(&eq.reactions, "guide.q", -0.2, 1e-12);
    assert_near(&eq.positions, "slider.x", -(0.2 * c), 1e-12);
    assert_near(&eq.reactions, "guide.limit", 2.0 * G * s, 1e-10 * G);
    assert!(
        (named(&eq.reactions, "guide.fy").abs() - 2.0 * G).abs() < 1e-10 * G,
        "{:?}",
        eq.reactions
    );
    assert!(named(&eq.reactions, "guide.fx").abs() < 1e-10 * G, "{:?}", eq.reactions);
}

#[test]
fn a_double_pendulum_on_a_stop_swings_about_its_lower_pin_alone() {
    // Two uniform rods (1 kg, 1 m) along +x, the upper pinned to the ground with stops
    // [−0.5, 0.5], the lower pinned to its end without: the upper rests on its lower stop
    // (hanging straight down lies beyond it), the lower hangs straight down from its end. The
    // stop carries the upper rod's weight torque and the lower's weight at the upper's end:
    // g (0.5 cos 0.5 + cos 0.5). With the upper rod held, one motion is left, the lower rod
    // swinging about its pin: ω² = m g (L/2) / (m L²/3) = 3 g / 2 (relative 1e-10).
    let toml = "[scene]\ngravity = [0.0, -9.81]\n\n\
        [[bodies]]\nname = \"lower\"\nmass = 1.0\nshape = { rod = 1.0 }\nposition = [1.5, 0.0]\n\n\
        [[bodies]]\nname = \"upper\"\nmass = 1.0\nshape = { rod = 1.0 }\nposition = [0.5, 0.0]\n\n\
        [[joints]]\nname = \"elbow\"\ntype = \"revolute\"\nbodies = [\"upper\", \"lower\"]\nat = [1.0, 0.0]\n\n\
        [[joints]]\nname = \"shoulder\"\ntype = \"revolute\"\nbodies = [\"ground\", \"upper\"]\nat = [0.0, 0.0]\nlimits = [-0.5, 0.5]\n";
    let scene = Scene::from_toml(toml, "double").unwrap();
    let modes = scene.modes().unwrap();
    let eq = &modes.equilibrium;
    assert_eq!(eq.held, ["shoulder"]);
    assert_near(&eq.reactions, "shoulder.q", -0.5, 1e-12);
    let torque = G * (0.5 * 0.5f64.cos() + 0.5f64.cos());
    assert_near(&eq.reactions, "shoulder.limit", torque, 1e-10 * G);
    // The lower rod hangs straight down from the upper's end.
    let end = (0.5f64.cos(), -(0.5f64.sin()));
    assert_near(&eq.positions, "lower.x", end.0, 1e-12);
    assert_near(&eq.positions, "lower.y", end.1 - 0.5, 1e-12);
    assert!(eq.stable);
    assert_eq!(modes.frequencies.len(), 1);
    let expected = (1.5 * G).sqrt() / (2.0 * std::f64::consts::PI);
    assert!(
        (modes.frequencies[0] - expected).abs() < 1e-10 * expected,
        "{} Hz, expected {expected}",
        modes.frequencies[0]
    );
}

#[test]
fn a_spatial_rod_rests_on_the_stop_of_its_revolute_joint_as_the_planar_one() {
    // The rod of the first test as a spatial body (its inertia about the pin's axis m L²/12) on a
    // revolute joint about −y, gravity along −z: its fall is a negative angle, as the planar
    // one's. The spatial row (body-frame angular velocities, the angle from the joint frames)
    // turns with the rod, so Newton's tangent lacks the stop's geometric stiffness; the
    // equilibrium is the same: on the lower stop with m g (L/2) cos 0.5, the pin carrying the
    // weight along z. Same tolerances.
    let text = "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
        [[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08333333333333333, 0.08333333333333333]\n\
        position = [0.5, 0.0, 0.0]\n\
        [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
        axis = [0.0, -1.0, 0.0]\nlimits = [-0.5, 0.5]\n";
    let eq = Scene::from_toml(text, "spatial rod").unwrap().equilibrium().unwrap();
    assert_eq!(eq.held, ["pin"]);
    // On the stop: the centre of mass 0.5 rad below the horizontal.
    let (s, c) = 0.5f64.sin_cos();
    assert_near(&eq.positions, "rod.x", 0.5 * c, 1e-12);
    assert_near(&eq.positions, "rod.z", -(0.5 * s), 1e-12);
    assert_near(&eq.reactions, "pin.limit", G * 0.5 * c, 1e-10 * G);
    assert!(
        (named(&eq.reactions, "pin.fz").abs() - G).abs() < 1e-10 * G,
        "{:?}",
        eq.reactions
    );
    assert!(eq.stable && eq.stiffness.is_empty());
}
