//! Compliant contact with a line or a plane on a moving body (`docs/contact.md`, "A line or plane
//! on a moving body"): a circle, a polygon or a rounded segment against a line fixed in another
//! planar body, a sphere, a box or a capsule against a plane fixed in another spatial body, which
//! feels the opposite force at the contact point. Checked against the ground's line or plane (a
//! platform welded to the ground moves nothing), against the conservation of momentum and of
//! energy between free bodies, the energy a strike takes seen from a moving frame, and a
//! spring-mounted platform's energy.

mod common;

use common::{check_strike, column, largest_difference, planar_momenta, run};
use dalembert::Scene;

/// A disk (1 kg, radius 0.1 m) thrown with spin at a line at y = 0, on the ground or on a
/// platform (3 kg, 0.6 × 0.1 m) welded to the ground with its top face at y = 0; Hertz 1e6,
/// dissipation 0.5 s/m, friction 0.4 below 1 mm/s; dopri5 1e-10 for 1 s.
fn disk_on(platform: bool) -> Scene {
    let (extra, line) = if platform {
        (
            "[[bodies]]\nname = \"platform\"\nmass = 3.0\nshape = { rectangle = [0.6, 0.1] }\nposition = [0.2, -0.05]\n\
             [[joints]]\nname = \"weld\"\ntype = \"rigid\"\nbodies = [\"ground\", \"platform\"]\nat = [0.2, -0.05]\n",
            "line = { body = \"platform\", point = [0.0, 0.0], normal = [0.0, 1.0] }",
        )
    } else {
        ("", "line = { point = [0.0, 0.0], normal = [0.0, 1.0] }")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"disk\"\nmass = 1.0\nshape = {{ disk = 0.1 }}\nposition = [0.0, 0.3]\n\
         velocity = [1.0, 0.0]\nangular_velocity = -20.0\n{extra}\
         [[forces]]\nname = \"touch\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = 0.1\n{line}\n\
         stiffness = 1e6\ndissipation = 0.5\nfriction = 0.4\nsmoothing_velocity = 1e-3\n\
         [simulation]\nend = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "disk.toml").unwrap()
}

#[test]
fn a_line_on_a_welded_platform_is_the_grounds_line() {
    // The same law computed on the ground's line and on a body's line held still by a weld: the
    // disk bounces, slides and rolls alike. Measured 8.5e-10 m apart (bar 1e-8 m: dopri5's 1e-10
    // on two runs whose steps differ) and 4.2e-5 N (bar 1e-4 N: the resting contact's stiffness
    // 1.5 k δ^(1/2) = 3.2e4 N/m and the regularized friction's slope μ F_n / v_s = 3.9e3 N·s/m
    // times those differences).
    let (ground, platform) = (run(&disk_on(false)), run(&disk_on(true)));
    for name in ["disk.x", "disk.y", "disk.angle"] {
        let off = largest_difference(&ground, &platform, name);
        assert!(off < 1e-8, "{name}: {off:.3e} apart");
    }
    for name in ["touch.fx", "touch.fy", "touch.normal"] {
        let off = largest_difference(&ground, &platform, name);
        assert!(off < 1e-4, "{name}: {off:.3e} N apart");
    }
    // It did touch, slide and bounce: a normal force well above the weight at the first bounce.
    let peak = column(&platform, "touch.normal").into_iter().fold(0.0, f64::max);
    assert!(peak > 20.0, "peak normal force {peak} N");
}

/// A disk (1 kg, radius 0.1 m, spinning) and a free plate (3 kg, 0.6 × 0.1 m) whose top face is
/// a line, closing on each other without gravity; the law with `dissipation`, `friction`;
/// dopri5 1e-11 for 0.3 s (one strike); both bodies' velocities plus `boost`.
fn strike(dissipation: f64, friction: f64, boost: [f64; 2]) -> Scene {
    let [u, w] = boost;
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0]\n\
         [[bodies]]\nname = \"disk\"\nmass = 1.0\nshape = {{ disk = 0.1 }}\nposition = [0.0, 0.3]\n\
         velocity = [{:?}, {:?}]\nangular_velocity = 5.0\n\
         [[bodies]]\nname = \"plate\"\nmass = 3.0\nshape = {{ rectangle = [0.6, 0.1] }}\nposition = [0.1, 0.0]\n\
         velocity = [{:?}, {:?}]\nangular_velocity = 1.0\n\
         [[forces]]\nname = \"touch\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = 0.1\n\
         line = {{ body = \"plate\", point = [0.1, 0.05], normal = [0.0, 1.0] }}\n\
         stiffness = 1e6\ndissipation = {dissipation}\nfriction = {friction}\nsmoothing_velocity = 1e-3\n\
         [simulation]\nend = 0.3\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.002\n",
        0.5 + u,
        -2.0 + w,
        u,
        0.5 + w
    );
    Scene::from_toml(&text, "strike.toml").unwrap()
}

/// Linear momentum `(px, py)` and angular momentum about the origin of the disk and the plate
/// along `scene`'s run, and its energy.
fn momenta(scene: &Scene) -> Vec<[f64; 4]> {
    planar_momenta(
        scene,
        &[("disk", 1.0, 0.5 * 0.01), ("plate", 3.0, 3.0 * (0.36 + 0.01) / 12.0)],
    )
}

#[test]
fn a_strike_on_a_free_plate_keeps_momentum_and_energy() {
    // With dissipation and friction: the contact's forces on the two bodies are equal and
    // opposite at one point, so momentum is kept (measured 3.6e-15 kg·m/s of 0.5; bar 1e-12,
    // round-off: a Runge–Kutta method keeps linear invariants exactly) and angular momentum
    // about the origin (measured 6.8e-15 of 0.12; bar 1e-9: dopri5's 1e-11 on a quadratic
    // invariant). The strike took energy.
    // The same strike seen from a frame moving at (3, −1) m/s: the contact's rate and sliding are
    // the bodies' relative velocities, so it takes the same energy (its momentum kept, the
    // change of T does not depend on the frame). Measured 4.4e-11 J apart (bar 1e-8 J of 1.7 J,
    // dopri5's 1e-11 on runs of different speeds); with the line's body's velocity left out of
    // the rate the dissipation would change with the frame.
    // Without dissipation and friction the contact is conservative on both bodies (its force at
    // the point is the gradient of k δ^(5/2) / (5/2), the plate's turning included): T + V kept to
    // 1e-8 J of 2.6 J (measured 2.5e-10 J).
    let runs = [(0.5, 0.4, [0.0, 0.0]), (0.5, 0.4, [3.0, -1.0]), (0.0, 0.0, [0.0, 0.0])]
        .map(|(d, mu, boost)| momenta(&strike(d, mu, boost)));
    let bars = [(0, 1e-12), (1, 1e-12), (2, 1e-9)];
    check_strike("disk", [&runs[0], &runs[1], &runs[2]], &bars, 0.1);
}

/// A rectangle (0.2 × 0.1 m, 1 kg) dropped turning onto a platform (2 kg) on a vertical guide,
/// held by a spring (2000 N/m) from the ground; no dissipation or friction; dopri5 1e-10 for 1 s.
fn block_on_spring_platform(shape: &str) -> Scene {
    let element = match shape {
        "polygon" => {
            "type = \"polygon-line\"\nbody = \"block\"\n\
                      vertices = [[-0.1, 0.25], [0.1, 0.25], [0.1, 0.35], [-0.1, 0.35]]\n"
        }
        _ => "type = \"segment-line\"\nbody = \"block\"\nat = [[-0.1, 0.3], [0.1, 0.3]]\nradius = 0.05\n",
    };
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"platform\"\nmass = 2.0\nshape = {{ rectangle = [0.6, 0.1] }}\nposition = [0.0, -0.05]\n\
         [[bodies]]\nname = \"block\"\nmass = 1.0\nshape = {{ rectangle = [0.2, 0.1] }}\nposition = [0.0, 0.3]\n\
         angle = 0.0\nangular_velocity = 3.0\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"platform\"]\nat = [0.0, -0.05]\naxis = [0.0, 1.0]\n\
         [[forces]]\nname = \"mount\"\ntype = \"spring-damper\"\nbodies = [\"ground\", \"platform\"]\n\
         at = [[0.0, -0.5], [0.0, -0.05]]\nstiffness = 2000.0\n\
         [[forces]]\nname = \"touch\"\n{element}line = {{ body = \"platform\", point = [0.0, 0.0], normal = [0.0, 1.0] }}\n\
         stiffness = 1e6\n\
         [simulation]\nend = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.005\n"
    );
    Scene::from_toml(&text, "block.toml").unwrap()
}

#[test]
fn a_block_on_a_spring_mounted_platform_keeps_its_energy() {
    // Corners (or end caps) strike the moving platform's line and the platform bounces on its
    // spring: T + V (the spring's and each corner's contact potential) kept to 1e-6 J, the bar of
    // the polygons on the ground's line (docs/contact.md; measured 2.0e-8 J with the polygon,
    // 3.1e-8 J with the segment, of an energy scale of about 2 J).
    for shape in ["polygon", "segment"] {
        let t = run(&block_on_spring_platform(shape));
        let e = column(&t, "energy");
        let off = e.iter().map(|x| (x - e[0]).abs()).fold(0.0, f64::max);
        assert!(off < 1e-6, "{shape}: T + V moved {off:.3e} J");
        let peak = column(&t, "touch.normal").into_iter().fold(0.0, f64::max);
        assert!(peak > 10.0, "{shape}: peak normal force {peak} N");
        let platform = column(&t, "platform.y");
        let moved = platform.iter().map(|y| (y - platform[0]).abs()).fold(0.0, f64::max);
        assert!(moved > 1e-3, "{shape}: the platform moved {moved} m");
    }
}

/// A ball (1 kg, radius 0.1 m) thrown with spin at a plane z = 0, of the ground or of a plate
/// (3 kg) welded to the ground with its top face there; Hertz 1e6, dissipation 0.5 s/m, friction
/// 0.4 below 1 mm/s; dopri5 1e-10 for 1 s.
fn ball_on(plate: bool) -> Scene {
    let (extra, plane) = if plate {
        (
            "[[bodies]]\nname = \"plate\"\nmass = 3.0\ninertia = [0.03, 0.03, 0.06]\nposition = [0.2, 0.0, -0.05]\n\
             [[joints]]\nname = \"weld\"\ntype = \"fixed\"\nbodies = [\"ground\", \"plate\"]\nat = [0.2, 0.0, -0.05]\n",
            "plane = { body = \"plate\", point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }",
        )
    } else {
        ("", "plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"ball\"\nmass = 1.0\ninertia = [0.004, 0.004, 0.004]\nposition = [0.0, 0.0, 0.3]\n\
         velocity = [1.0, 0.5, 0.0]\nangular_velocity = [3.0, -20.0, 1.0]\n{extra}\
         [[forces]]\nname = \"touch\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = 0.1\n{plane}\n\
         stiffness = 1e6\ndissipation = 0.5\nfriction = 0.4\nsmoothing_velocity = 1e-3\n\
         [simulation]\nend = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "ball.toml").unwrap()
}

#[test]
fn a_plane_on_a_welded_plate_is_the_grounds_plane() {
    // As the disk on the welded platform, in space, with the same bars for the same reasons:
    // measured 2.4e-10 m and 1.3e-5 N apart.
    let (ground, plate) = (run(&ball_on(false)), run(&ball_on(true)));
    for (names, bar) in [
        (&["ball.x", "ball.y", "ball.z"][..], 1e-8),
        (&["touch.fx", "touch.fy", "touch.fz", "touch.normal"][..], 1e-4),
    ] {
        for name in names {
            let off = largest_difference(&ground, &plate, name);
            assert!(off < bar, "{name}: {off:.3e} apart");
        }
    }
    let peak = column(&plate, "touch.normal").into_iter().fold(0.0, f64::max);
    assert!(peak > 20.0, "peak normal force {peak} N");
}

/// A sphere, a box or a capsule (`element`'s keys, on the body `solid`: 1 kg) and a free plate
/// (3 kg) whose top face is a plane, closing on each other without gravity, both turning; the
/// law with `dissipation`, `friction`; both bodies' velocities plus `boost`; dopri5 1e-11 for
/// 0.3 s.
fn strike3(element: &str, dissipation: f64, friction: f64, boost: [f64; 3]) -> Scene {
    let [u, v, w] = boost;
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
         [[bodies]]\nname = \"solid\"\nmass = 1.0\ninertia = [0.004, 0.005, 0.006]\nposition = [0.0, 0.0, 0.3]\n\
         velocity = [{:?}, {:?}, {:?}]\nangular_velocity = [2.0, 5.0, -1.0]\n\
         [[bodies]]\nname = \"plate\"\nmass = 3.0\ninertia = [0.03, 0.04, 0.06]\nposition = [0.1, 0.05, 0.0]\n\
         velocity = [{u:?}, {v:?}, {:?}]\nangular_velocity = [0.5, -0.3, 1.0]\n\
         [[forces]]\nname = \"touch\"\n{element}\nbody = \"solid\"\n\
         plane = {{ body = \"plate\", point = [0.1, 0.05, 0.05], normal = [0.0, 0.0, 1.0] }}\n\
         stiffness = 1e6\ndissipation = {dissipation}\nfriction = {friction}\nsmoothing_velocity = 1e-3\n\
         [simulation]\nend = 0.3\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.002\n",
        0.5 + u,
        0.2 + v,
        -2.0 + w,
        0.5 + w
    );
    Scene::from_toml(&text, "strike3.toml").unwrap()
}

/// Linear momentum of the solid and the plate along `scene`'s run, and its energy.
fn momenta3(scene: &Scene) -> Vec<[f64; 4]> {
    let t = run(scene);
    let c = |n: &str| column(&t, n);
    let v: Vec<_> = [("solid", 1.0), ("plate", 3.0)]
        .iter()
        .map(|(b, m)| (["vx", "vy", "vz"].map(|k| c(&format!("{b}.{k}"))), *m))
        .collect();
    let energy = c("energy");
    (0..energy.len())
        .map(|k| {
            let mut out = [0.0, 0.0, 0.0, energy[k]];
            for (vs, m) in &v {
                for i in 0..3 {
                    out[i] += m * vs[i][k];
                }
            }
            out
        })
        .collect()
}

#[test]
fn a_strike_on_a_free_turning_plate_keeps_momentum_and_energy_in_space() {
    // A sphere, a box (its corners) and a capsule (its end caps) strike a plate turning about a
    // tilted axis. With dissipation and friction momentum is kept to round-off (measured 4.2e-15
    // at most; bar 1e-12) and the strike takes the same energy seen from a frame moving at
    // (3, −1, 2) m/s (measured 2.5e-9 J at most, of 1.7 to 2.0 J; bar 1e-8 J, dopri5's 1e-11 on
    // runs of different speeds); without them T + V is kept (measured 1.4e-9 J at most of 2.6 J;
    // bar 1e-8 J: the force at each point is the gradient of the contact's potential on both
    // bodies, the plate's turning included).
    let elements = [
        ("sphere", "type = \"sphere-plane\"\nradius = 0.1"),
        ("box", "type = \"box-plane\"\nsize = [0.2, 0.15, 0.1]"),
        (
            "capsule",
            "type = \"capsule-plane\"\nat = [[-0.1, 0.0, 0.3], [0.1, 0.0, 0.3]]\nradius = 0.05",
        ),
    ];
    for (what, element) in elements {
        let runs = [(0.5, 0.4, [0.0; 3]), (0.5, 0.4, [3.0, -1.0, 2.0]), (0.0, 0.0, [0.0; 3])]
            .map(|(d, mu, boost)| momenta3(&strike3(element, d, mu, boost)));
        let bars = [(0, 1e-12), (1, 1e-12), (2, 1e-12)];
        check_strike(what, [&runs[0], &runs[1], &runs[2]], &bars, 0.05);
    }
}
