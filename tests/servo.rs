//! The joint servo (`[[forces]] type = "servo"`, `docs/scenes.md`; what an MJCF `position`
//! actuator becomes, `docs/import.md`) against closed forms, on a rod pinned at its end about the
//! z axis with no gravity, `J_O = I_zz + m d² = 0.08 + 1 × 0.5² = 0.33 kg m²`:
//!
//! - a step to a fixed target: `J θ̈ = −k (θ − θ*) − c θ̇`, the damped oscillator's step response
//!   `θ = θ* (1 − e^{−ζωt} (cos ω_d t + ζω/ω_d sin ω_d t))`;
//! - a far target with the torque held at its range's bound: `θ = ½ (τ_max / J) t²` while
//!   `k (θ* − θ) > τ_max`;
//! - a target given by a named input, moved between steps: the step response from each switch.

use dalembert::Scene;
use std::sync::atomic::AtomicBool;

const J: f64 = 0.33;

/// A body on one joint to the ground (`body` and `joint` their TOML keys besides the names), with
/// no gravity and a servo named "servo" on the joint (`servo` its keys).
fn one_joint(body: &str, joint: &str, servo: &str, settings: &str) -> Scene {
    let toml = format!(
        "[scene]\ngravity = [0.0, 0.0, 0.0]\n\n[[bodies]]\nname = \"body\"\n{body}\n\n[[joints]]\nname = \"j\"\n\
         bodies = [\"ground\", \"body\"]\n{joint}\n\n[[forces]]\nname = \"servo\"\ntype = \"servo\"\njoint = \"j\"\n{servo}\n\n\
         [simulation]\n{settings}\n"
    );
    Scene::from_toml(&toml, "servo").unwrap()
}

/// The rod and its servo.
fn rod(servo: &str, settings: &str) -> Scene {
    one_joint(
        "mass = 1.0\ninertia = [0.001, 0.08, 0.08]\nposition = [0.5, 0.0, 0.0]",
        "at = [0.0, 0.0, 0.0]\ntype = \"revolute\"\naxis = [0.0, 0.0, 1.0]",
        servo,
        settings,
    )
}

/// The step response of `J θ̈ + c θ̇ + k θ = k θ*` from rest at 0 (under-damped), `J` the rod's.
fn step_response(k: f64, c: f64, aim: f64, t: f64) -> f64 {
    response(J, k, c, aim, t)
}

/// The step response of `m ẍ + c ẋ + k x = k x*` from rest at 0 (under-damped).
fn response(m: f64, k: f64, c: f64, aim: f64, t: f64) -> f64 {
    let omega = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let damped = omega * (1.0 - zeta * zeta).sqrt();
    aim * (1.0 - (-zeta * omega * t).exp() * ((damped * t).cos() + zeta * omega / damped * (damped * t).sin()))
}

/// Every formulation in absolute coordinates, and the tree in joint coordinates (where the
/// servo's angle is the joint's coordinate).
const FORMULATIONS: [&str; 4] = [
    "augmented\"\ncoordinates = \"absolute",
    "embedding",
    "amalgamated",
    "augmented\"\ncoordinates = \"joint",
];

#[test]
fn a_servo_steps_to_its_target_as_a_damped_oscillator() {
    // ω = 5.5 rad/s, ζ = 0.094: four oscillations in 2 s. Dormand–Prince at 1e-11: the angle
    // within 1e-8 rad at every sample (a sign error, a wrong gain or a missing damping is off by
    // 1e-2 or more).
    let (k, c, aim) = (10.0, 0.34, 0.5);
    for formulation in FORMULATIONS {
        let scene = rod(
            &format!("stiffness = {k}\ndamping = {c}\ntarget = {aim}"),
            &format!("end = 2.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-12\nformulation = \"{formulation}\""),
        );
        let run = scene.record(&AtomicBool::new(false));
        assert!(run.outcome.is_ok(), "{formulation}: {:?}", run.outcome);
        let (t, q) = (run.table.column("t").unwrap(), run.table.column("j.q").unwrap());
        assert!(t.len() > 100);
        for (t, q) in t.iter().zip(&q) {
            let want = step_response(k, c, aim, *t);
            assert!((q - want).abs() < 1e-8, "{formulation} t = {t}: {q} vs {want}");
        }
    }
}

#[test]
fn a_servo_held_at_its_range_accelerates_the_rod_uniformly() {
    // k (θ* − θ) = 100 (1 − θ) exceeds 0.5 N·m until θ = 0.995, reached at t = 1.146 s: until
    // then the torque is the bound and θ = ½ (0.5 / J) t². Checked to 1 s, 1e-9 rad.
    for formulation in FORMULATIONS {
        let scene = rod(
            "stiffness = 100.0\ntarget = 1.0\nrange = [-0.5, 0.5]",
            &format!("end = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-12\nformulation = \"{formulation}\""),
        );
        let run = scene.record(&AtomicBool::new(false));
        assert!(run.outcome.is_ok(), "{formulation}: {:?}", run.outcome);
        let (t, q) = (run.table.column("t").unwrap(), run.table.column("j.q").unwrap());
        for (t, q) in t.iter().zip(&q) {
            let want = 0.5 * (0.5 / J) * t * t;
            assert!((q - want).abs() < 1e-9, "{formulation} t = {t}: {q} vs {want}");
        }
        assert!(q.last().unwrap() > &0.75, "the rod turns");
    }
}

#[test]
fn a_servo_follows_a_target_set_between_steps() {
    // The target is the input 'aim': 0.5 from t = 0, then 0.2 from t = 1 s. From the state at
    // the switch the response is the oscillator's with that initial state; checked at t = 2 s
    // against the superposition of the two steps (linear system: 0.5 step from 0, −0.3 step from
    // 1 s), 1e-8 rad.
    let (k, c) = (10.0, 0.34);
    for formulation in FORMULATIONS {
        let scene = rod(
            &format!("stiffness = {k}\ndamping = {c}\ntarget = {{ input = \"aim\" }}"),
            &format!("end = 2.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-12\nformulation = \"{formulation}\""),
        );
        let mut sim = scene.simulator().unwrap();
        sim.set_input("aim", 0.5).unwrap();
        sim.advance_to(1.0).unwrap();
        let at_switch = sim.value("j.q").unwrap();
        assert!(
            (at_switch - step_response(k, c, 0.5, 1.0)).abs() < 1e-8,
            "{formulation}"
        );
        sim.set_input("aim", 0.2).unwrap();
        sim.advance_to(2.0).unwrap();
        let want = step_response(k, c, 0.5, 2.0) + step_response(k, c, -0.3, 1.0);
        let got = sim.value("j.q").unwrap();
        assert!((got - want).abs() < 1e-8, "{formulation}: {got} vs {want}");
    }
}

/// A block (2 kg) on a prismatic joint along x, no gravity: a servo on a slide pushes along the
/// axis, `m s̈ = −k (s − s*) − c ṡ`, the step response of [`step_response`] with `J` replaced by
/// the mass; and held at its range, `s = ½ (F_max / m) t²`.
fn block(servo: &str, settings: &str) -> Scene {
    one_joint(
        "mass = 2.0\ninertia = [0.01, 0.01, 0.01]\nposition = [0.3, 0.2, 0.0]",
        "at = [0.3, 0.2, 0.0]\ntype = \"prismatic\"\naxis = [1.0, 0.0, 0.0]",
        servo,
        settings,
    )
}

#[test]
fn a_servo_on_a_slide_moves_its_block_as_the_closed_forms() {
    // k = 50 N/m, c = 2 N s/m on 2 kg: ω = 5 rad/s, ζ = 0.1; 1e-8 m at every sample. Then
    // k = 400, target 1 m, range ±3 N: 400 (1 − s) > 3 until s = 0.9925, reached at 1.41 s, so to
    // 1 s the block accelerates at 1.5 m/s², 1e-9 m.
    let mass = 2.0;
    for formulation in FORMULATIONS {
        let settings =
            format!("end = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-12\nformulation = \"{formulation}\"");
        let run = block("stiffness = 50.0\ndamping = 2.0\ntarget = 0.4", &settings).record(&AtomicBool::new(false));
        assert!(run.outcome.is_ok(), "{formulation}: {:?}", run.outcome);
        let (t, s) = (run.table.column("t").unwrap(), run.table.column("j.q").unwrap());
        for (t, s) in t.iter().zip(&s) {
            let want = response(mass, 50.0, 2.0, 0.4, *t);
            assert!((s - want).abs() < 1e-8, "{formulation} t = {t}: {s} vs {want}");
        }
        let run =
            block("stiffness = 400.0\ntarget = 1.0\nrange = [-3.0, 3.0]", &settings).record(&AtomicBool::new(false));
        assert!(run.outcome.is_ok(), "{formulation}: {:?}", run.outcome);
        let (t, s) = (run.table.column("t").unwrap(), run.table.column("j.q").unwrap());
        for (t, s) in t.iter().zip(&s) {
            let want = 0.5 * (3.0 / mass) * t * t;
            assert!((s - want).abs() < 1e-9, "{formulation} t = {t}: {s} vs {want}");
        }
        assert!(s.last().unwrap() > &0.7, "the block moves");
    }
}

#[test]
fn a_spring_across_the_half_turn_pulls_the_same_way_in_both_coordinates() {
    // Free angle 2.5 rad, the rod started at −1 rad: the model measures the deflection within a
    // half turn, −1 − 2.5 + 2π = 2.78 rad, so the spring turns the rod further negative (toward
    // 2.5 − 2π). Joint coordinates must take the same deflection, not −3.5 (which pulls the other
    // way): both runs end at the same angle (1e-9 rad; dopri5 at 1e-11) and it is below −1.
    let mut ends = Vec::new();
    for coordinates in ["absolute", "joint"] {
        let scene = Scene::from_toml(
            &format!(
                "[scene]\ngravity = [0.0, 0.0, 0.0]\n\n[[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08, 0.08]\n\
                 position = [0.5, 0.0, 0.0]\n\n[[joints]]\nname = \"pin\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
                 type = \"revolute\"\naxis = [0.0, 0.0, 1.0]\n\n[[forces]]\nname = \"spring\"\ntype = \"rotational-spring-damper\"\n\
                 joint = \"pin\"\nstiffness = 1.0\nfree_angle = 2.5\n\n[initial]\njoints = {{ pin = -1.0 }}\n\n\
                 [simulation]\nend = 0.2\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-12\ncoordinates = \"{coordinates}\"\n"
            ),
            "spring",
        )
        .unwrap();
        let run = scene.record(&AtomicBool::new(false));
        assert!(run.outcome.is_ok(), "{coordinates}: {:?}", run.outcome);
        ends.push(*run.table.column("pin.q").unwrap().last().unwrap());
    }
    assert!(ends[0] < -1.1, "the spring turns the rod negative: {ends:?}");
    assert!((ends[0] - ends[1]).abs() < 1e-9, "{ends:?}");
}
