//! Compliant contact with a cam profile (`circle-profile` and `line-profile` without `rigid`,
//! `docs/contact.md`, "Cams") against numbers from elsewhere: a roller and a flat face resting on
//! a profile press in by Hertz's `(m g / k)^(1/n)` whichever way the profile's points run; a cam
//! turning freely under a spring-loaded roller or face without dissipation keeps `T + V` (the
//! contact's potential counted); with a stiff contact the roller follows the rigid contact's lift
//! less Hertz's quasi-static sink.

mod common;

use common::{column, run};
use dalembert::Scene;
use std::f64::consts::PI;

/// The profile key: a circle of radius `r` about `(cx, cy)`, 64 points from its top, clockwise
/// or not, the last repeating the first, on `body`.
fn circle_profile(body: &str, r: f64, (cx, cy): (f64, f64), clockwise: bool) -> String {
    let sign = if clockwise { -1.0 } else { 1.0 };
    let points: Vec<String> = (0..=64)
        .map(|k| {
            let a = PI / 2.0 + sign * 2.0 * PI * (k % 64) as f64 / 64.0;
            format!("[{:?}, {:?}]", cx + r * a.cos(), cy + r * a.sin())
        })
        .collect();
    format!("profile = {{ body = \"{body}\", points = [{}] }}", points.join(", "))
}

/// A follower of 0.5 kg on a vertical guide over a profile of the ground (a circle of radius
/// 0.05 about the origin), touching its top with `element` (a roller of radius 0.02 centred at
/// 0.07, or a face at 0.05: `Y` in it stands for the follower's height), settling with dissipation 5 s/m; dopri5 at 1e-10 for 3 s.
fn resting(element: &str, clockwise: bool) -> Scene {
    let y = if element.contains("circle-profile") { 0.07 } else { 0.05 };
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"follower\"\nmass = 0.5\ninertia = 1e-4\nposition = [0.0, {y}]\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"follower\"]\nat = [0.0, {y}]\naxis = [0.0, 1.0]\n\
         [[forces]]\nname = \"touch\"\n{}\nbody = \"follower\"\n{}\ndissipation = 5.0\n\
         [simulation]\nend = 3.0\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n",
        element.replace('Y', &format!("{y:?}")),
        circle_profile("ground", 0.05, (0.0, 0.0), clockwise)
    );
    Scene::from_toml(&text, "resting on a profile").unwrap()
}

#[test]
fn a_roller_and_a_face_resting_on_a_profile_press_in_by_hertz_law() {
    // The profile's top is one of its points (the spline passes through them, and is level there
    // by symmetry), so the follower rests at its height plus the roller's radius less Hertz's
    // δ = (m g / k)^(1/n): k = 1e7 N/m^1.5 with n = 3/2 for the roller, k = 1e6 N/m with n = 1
    // for the face. Within 1e-10 m after 3 s (dopri5 at 1e-10; measured 1.5e-12 and 1.6e-12 m,
    // what the run's tolerance leaves of the contact's vibration), the profile's points running
    // either way round; the normal force m g within 1e-4 N (the contact's stiffness at rest, up
    // to 1e6 N/m, times that tolerance; measured 1.8e-7 and 1.6e-6 N).
    let mg: f64 = 0.5 * 9.81;
    let cases = [
        (
            "roller",
            "type = \"circle-profile\"\nradius = 0.02\nstiffness = 1e7",
            0.07 - (mg / 1e7).powf(1.0 / 1.5),
        ),
        (
            "face",
            "type = \"line-profile\"\nline = { point = [0.0, Y], normal = [0.0, -1.0] }\nstiffness = 1e6\nexponent = 1.0",
            0.05 - mg / 1e6,
        ),
    ];
    for (what, element, expected) in cases {
        for clockwise in [false, true] {
            let table = run(&resting(element, clockwise));
            let y = *column(&table, "follower.y").last().unwrap();
            let normal = *column(&table, "touch.normal").last().unwrap();
            assert!(
                (y - expected).abs() < 1e-10,
                "{what}, clockwise {clockwise}: rests at {y}, expected {expected}"
            );
            assert!(
                (normal - mg).abs() < 1e-4,
                "{what}, clockwise {clockwise}: presses with {normal} N"
            );
        }
    }
}

/// A cam (1 kg, J = 0.05 kg·m²: 10 J at the start, enough to lift the follower over its top)
/// turning freely about the origin at 20 rad/s, its profile a circle of radius 0.05 about
/// (0, 0.01): an eccentric at its top, the follower at rest there; a follower of 0.5 kg on a
/// vertical guide over
/// the origin, on it with `element` and pressed onto it by a spring (200 N/m, compressed about
/// 0.4 m); no dissipation or friction; dopri5 at 1e-11 for 1 s.
fn free_cam(element: &str) -> Scene {
    // Set down pressed in by the spring's and the weight's 84.9 N at rest (Hertz's exponent 3/2
    // for the roller, 1 for the face, k = 1e7), so that the contact does not ring.
    let y: f64 = if element.contains("circle-profile") {
        0.08 - (84.905f64 / 1e7).powf(1.0 / 1.5)
    } else {
        0.06 - 84.905 / 1e7
    };
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"cam\"\nmass = 1.0\ninertia = 0.05\nposition = [0.0, 0.0]\nangular_velocity = 20.0\n\
         [[bodies]]\nname = \"follower\"\nmass = 0.5\ninertia = 1e-4\nposition = [0.0, {y}]\n\
         [[joints]]\nname = \"shaft\"\ntype = \"revolute\"\nbodies = [\"ground\", \"cam\"]\nat = [0.0, 0.0]\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"follower\"]\nat = [0.0, {y}]\naxis = [0.0, 1.0]\n\
         [[forces]]\nname = \"spring\"\ntype = \"spring-damper\"\nbodies = [\"ground\", \"follower\"]\n\
         at = [[0.0, {}], [0.0, {y}]]\nstiffness = 200.0\nfree_length = 0.9\n\
         [[forces]]\nname = \"touch\"\n{}\nbody = \"follower\"\n{}\n\
         [simulation]\nend = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.002\n",
        y + 0.5,
        element.replace('Y', &format!("{y:?}")),
        circle_profile("cam", 0.05, (0.0, 0.01), false)
    );
    Scene::from_toml(&text, "a free cam").unwrap()
}

#[test]
fn a_free_cam_under_a_roller_or_a_face_keeps_its_energy() {
    // Without dissipation and friction the contact force is the gradient of k δⁿ⁺¹ / (n + 1)
    // (the closest point's slide along the profile changes δ by nothing to first order), so
    // the cam, the follower, the spring, gravity and the contact exchange energy and keep its
    // sum (a conservation law): within 1e-9 J of 26 J while the cam turns three times (dopri5 at
    // 1e-11; measured 6.0e-11 J under the roller, 1.0e-11 J under the face).
    let cases = [
        ("roller", "type = \"circle-profile\"\nradius = 0.02\nstiffness = 1e7"),
        (
            "face",
            "type = \"line-profile\"\nline = { point = [0.0, Y], normal = [0.0, -1.0] }\nstiffness = 1e7\nexponent = 1.0",
        ),
    ];
    for (what, element) in cases {
        let table = run(&free_cam(element));
        let (energy, normal) = (column(&table, "energy"), column(&table, "touch.normal"));
        let angle = *column(&table, "cam.angle").last().unwrap();
        assert!(angle > 2.0 * PI, "{what}: the cam turned only {angle} rad");
        assert!(normal.iter().all(|&n| n > 0.0), "{what}: the follower left the cam");
        let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
        assert!(drift < 1e-9, "{what}: the energy moved {drift:e} J from {}", energy[0]);
    }
}

#[test]
fn a_stiff_roller_follows_the_rigid_contacts_lift() {
    // scenes/cam-roller.toml (a roller on a disk cam driven at 2 turns per second, RK4 at 0.1 ms)
    // with its rigid contact, and again compliant: k = 1e9 N/m^1.5 (Hertz's 3/2), d = 20 s/m. Once
    // the start's ringing has died (after 0.2 s), the compliant follower rides the rigid one's
    // lift less Hertz's quasi-static sink (N/k)^(2/3) under the rigid contact's force N: within
    // 1e-6 m (measured 1.5e-7 m; the sink itself is up to 9.6e-6 m), and presses with the rigid
    // contact's force within 1e-2 N (measured 2.3e-3 N: the dissipation's share of the force as
    // the sink changes).
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cam-roller.toml");
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains("\nrigid = true\n"));
    let compliant = text.replace("\nrigid = true\n", "\nstiffness = 1e9\ndissipation = 20.0\n");
    let rigid = run(&Scene::from_toml(&text, "rigid roller").unwrap());
    let soft = run(&Scene::from_toml(&compliant, "compliant roller").unwrap());
    let (t, y_rigid, n_rigid) = (
        column(&rigid, "t"),
        column(&rigid, "follower.y"),
        column(&rigid, "roller.normal"),
    );
    let (y_soft, n_soft) = (column(&soft, "follower.y"), column(&soft, "roller.normal"));
    assert_eq!(t.len(), y_soft.len());
    let (mut lift, mut force, mut sink) = (0.0f64, 0.0f64, 0.0f64);
    for i in (0..t.len()).filter(|&i| t[i] >= 0.2) {
        let hertz = (n_rigid[i] / 1e9).powf(1.0 / 1.5);
        lift = lift.max((y_soft[i] - (y_rigid[i] - hertz)).abs());
        force = force.max((n_soft[i] - n_rigid[i]).abs());
        sink = sink.max(hertz);
    }
    assert!(sink > 5e-6, "the sink {sink} m is too small to tell the contacts apart");
    assert!(
        lift < 1e-6,
        "the compliant lift is {lift:e} m off the rigid one less the sink"
    );
    assert!(force < 1e-2, "the normal forces differ by {force:e} N");
}
