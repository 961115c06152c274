//! Coulomb friction in rigid contact (`docs/limits.md`, "Friction in rigid contact"), against
//! closed forms: a disk thrown on a floor slides, decelerating at `μ g` while its spin grows at
//! `2 μ g / R`, until it rolls at two thirds of its speed, and then rolls without creep; the same
//! on a free plate, whose momentum it shares; a disk on an incline rolls at `(2/3) g sin α` where
//! `tan α ≤ 3 μ` and slides at `g (sin α − μ cos α)` otherwise; a spinning disk dropped on a floor
//! leaves with the tangential impulse of Coulomb's law (the one that stops its slip, or `μ P_n`);
//! a disk rolling off the top of a fixed cylinder has the rolling friction and normal force of the
//! free-body diagram, until its friction reaches `μ N`, where it slips. Every formulation, RK4 and
//! dopri5, and the energy balance `E − W` closes.

mod common;

use common::{balance_drift, column, run};
use dalembert::Scene;

const G: f64 = 9.81;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];
const METHODS: [&str; 2] = ["rk4", "dopri5"];
/// The disk's mass (kg) and radius (m): `I = m R² / 2`.
const M: f64 = 2.0;
const R: f64 = 0.1;

/// A disk (2 kg, radius 0.1 m) at `at` with velocity `velocity` and spin `spin`, in rigid contact
/// with friction `mu` (restitution `e`) with a line through the origin with normal `normal`,
/// fixed in the ground or in `platform` (then `platform_joint` holds it), run to `end` by
/// `formulation` and `integrator`.
struct Disk<'a> {
    at: [f64; 2],
    velocity: [f64; 2],
    spin: f64,
    mu: f64,
    e: f64,
    normal: [f64; 2],
    platform: Option<(&'a str, &'a str)>,
}

impl Disk<'_> {
    fn scene(&self, formulation: &str, integrator: &str, end: f64) -> Scene {
        let (platform, line_body) = match self.platform {
            Some((body, joint)) => (
                format!("[[bodies]]\nname = \"plate\"\nmass = 4.0\nshape = {{ rectangle = [2.0, 0.1] }}\nposition = [0.0, -0.05]\n{body}[[joints]]\nname = \"guide\"\nbodies = [\"ground\", \"plate\"]\nat = [0.0, -0.05]\n{joint}"),
                "body = \"plate\", ",
            ),
            None => (String::new(), ""),
        };
        let text = format!(
            "[scene]\ngravity = [0.0, {}]\n\
             [[bodies]]\nname = \"disk\"\nmass = {M}\nshape = {{ disk = {R} }}\nposition = [{}, {}]\n\
             velocity = [{}, {}]\nangular_velocity = {}\n\
             {platform}\
             [[forces]]\nname = \"floor\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = {R}\n\
             line = {{ {line_body}point = [0.0, 0.0], normal = [{}, {}] }}\nrigid = true\nfriction = {}\nrestitution = {}\n\
             [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
             step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
            -G,
            self.at[0],
            self.at[1],
            self.velocity[0],
            self.velocity[1],
            self.spin,
            self.normal[0],
            self.normal[1],
            self.mu,
            self.e
        );
        Scene::from_toml(&text, "disk").unwrap()
    }
}

#[test]
fn a_disk_thrown_on_a_floor_slides_then_rolls_at_two_thirds_of_its_speed() {
    // Sliding, `ẍ = −μ g` and `ω̇ = −2 μ g / R` (the friction `μ m g` at the contact point, `I = m
    // R²/2`), until the contact point's speed `ẋ + ω R` reaches zero at `t* = v₀ / (3 μ g)`; then it
    // rolls at `2 v₀ / 3` with no friction. The floor is the ground's line, or the top of a plate
    // welded to the ground (the line of a body). The slip stops at an event located to 1e-9 m/s of
    // its rate (a thousandth of the stick speed), which the impulse at the event takes back: the bar
    // 1e-10 m on positions, 1e-9 m/s on speeds is far above that and far below any creep.
    let (v0, mu) = (3.0, 0.3);
    let t_star = v0 / (3.0 * mu * G);
    let exact = |t: f64| -> [f64; 3] {
        let s = t.min(t_star);
        let x = v0 * s - 0.5 * mu * G * s * s + 2.0 * v0 / 3.0 * (t - s);
        [x, v0 - mu * G * s, -2.0 * mu * G * s / R]
    };
    for platform in [None, Some(("", "type = \"rigid\"\n"))] {
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let disk = Disk {
                    at: [0.0, R],
                    velocity: [v0, 0.0],
                    spin: 0.0,
                    mu,
                    e: 0.0,
                    normal: [0.0, 1.0],
                    platform,
                };
                let scene = disk.scene(formulation, integrator, 1.0);
                let what = format!(
                    "{formulation} {integrator} on the {}",
                    if platform.is_some() { "plate" } else { "ground" }
                );
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, vx, omega, y) = (c("t"), c("disk.x"), c("disk.vx"), c("disk.omega"), c("disk.y"));
                let (friction, normal) = (c("floor.friction"), c("floor.normal"));
                for k in 0..t.len() {
                    let [xe, ve, we] = exact(t[k]);
                    assert!((x[k] - xe).abs() < 1e-10, "{what}: x({}) = {} against {xe}", t[k], x[k]);
                    assert!(
                        (vx[k] - ve).abs() < 1e-9,
                        "{what}: ẋ({}) = {} against {ve}",
                        t[k],
                        vx[k]
                    );
                    assert!(
                        (omega[k] - we).abs() < 1e-8,
                        "{what}: ω({}) = {} against {we}",
                        t[k],
                        omega[k]
                    );
                    assert!((y[k] - R).abs() < 1e-12, "{what}: the disk left the floor ({})", y[k]);
                    // The friction: −μ m g while it slides, none while it rolls (1e-9 N: round-off
                    // of the 19.62 N load).
                    let f = if t[k] < t_star { -mu * M * G } else { 0.0 };
                    if (t[k] - t_star).abs() > 1e-3 {
                        assert!(
                            (friction[k] - f).abs() < 1e-9,
                            "{what}: friction({}) = {}",
                            t[k],
                            friction[k]
                        );
                    }
                    assert!(
                        (normal[k] - M * G).abs() < 1e-9,
                        "{what}: normal({}) = {}",
                        t[k],
                        normal[k]
                    );
                }
                // The kinetic energy lost is the friction's work, m v₀² / 6 (1e-9 J of 9 J).
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}

#[test]
fn a_disk_thrown_on_a_free_plate_shares_its_momentum_until_it_rolls() {
    // The plate (4 kg) slides on a frictionless horizontal guide: the friction −μ m g on the disk
    // pushes it at μ m g / M. The slip rate falls at μ g (3 + m/M) and reaches zero at
    // t* = v₀ / (μ g (3 + m/M)); then both move at constant speeds (no horizontal force). The
    // momentum m ẋ + M Ẋ stays m v₀ throughout (to round-off).
    let (v0, mu, plate) = (3.0, 0.3, 4.0);
    let t_star = v0 / (mu * G * (3.0 + M / plate));
    let exact = |t: f64| -> [f64; 2] {
        let s = t.min(t_star);
        let x = v0 * s - 0.5 * mu * G * s * s + (v0 - mu * G * s) * (t - s);
        let a = mu * M * G / plate;
        [x, 0.5 * a * s * s + a * s * (t - s)]
    };
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let disk = Disk {
                at: [0.0, R],
                velocity: [v0, 0.0],
                spin: 0.0,
                mu,
                e: 0.0,
                normal: [0.0, 1.0],
                platform: Some(("", "type = \"prismatic\"\naxis = [1.0, 0.0]\n")),
            };
            let scene = disk.scene(formulation, integrator, 1.0);
            let what = format!("{formulation} {integrator}");
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (t, x, px, vx, pvx) = (c("t"), c("disk.x"), c("plate.x"), c("disk.vx"), c("plate.vx"));
            for k in 0..t.len() {
                let [xe, pe] = exact(t[k]);
                assert!(
                    (x[k] - xe).abs() < 1e-10,
                    "{what}: disk x({}) = {} against {xe}",
                    t[k],
                    x[k]
                );
                assert!(
                    (px[k] - pe).abs() < 1e-10,
                    "{what}: plate x({}) = {} against {pe}",
                    t[k],
                    px[k]
                );
                let momentum = M * vx[k] + plate * pvx[k];
                assert!((momentum - M * v0).abs() < 1e-12, "{what}: momentum {momentum}");
            }
            let drift = balance_drift(&scene);
            assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
        }
    }
}

#[test]
fn a_disk_on_an_incline_rolls_or_slides_as_the_closed_forms_say() {
    // Released at rest on an incline of angle α (μ = 0.2): where tan α ≤ 3 μ it rolls, its centre
    // moving s = g sin α t² / 6 down the slope, its friction (1/3) m g sin α up it, its angle s / R;
    // otherwise it slides, s = g (sin α − μ cos α) t² / 2, its friction μ m g cos α up the slope, and
    // it spins up at 2 μ g cos α / R. The tangent of the output is (n_y, −n_x), up the slope.
    let mu = 0.2;
    for alpha in [20f64.to_radians(), 40f64.to_radians()] {
        let rolls = alpha.tan() <= 3.0 * mu;
        let (s_rate, force, spin) = if rolls {
            (
                G * alpha.sin() / 3.0,
                M * G * alpha.sin() / 3.0,
                G * alpha.sin() / (3.0 * R),
            )
        } else {
            let a = G * (alpha.sin() - mu * alpha.cos());
            (a / 2.0, mu * M * G * alpha.cos(), mu * G * alpha.cos() / R)
        };
        let normal = [-alpha.sin(), alpha.cos()];
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let disk = Disk {
                    at: [R * normal[0], R * normal[1]],
                    velocity: [0.0, 0.0],
                    spin: 0.0,
                    mu,
                    e: 0.0,
                    normal,
                    platform: None,
                };
                let scene = disk.scene(formulation, integrator, 1.0);
                let what = format!("{formulation} {integrator} at α = {:.0}°", alpha.to_degrees());
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, y, angle, friction) =
                    (c("t"), c("disk.x"), c("disk.y"), c("disk.angle"), c("floor.friction"));
                for k in 0..t.len() {
                    // Down the slope: −(cos α, sin α).
                    let s = -(x[k] - R * normal[0]) * alpha.cos() - (y[k] - R * normal[1]) * alpha.sin();
                    let se = s_rate * t[k] * t[k];
                    assert!((s - se).abs() < 1e-10, "{what}: s({}) = {s} against {se}", t[k]);
                    let ae = spin * t[k] * t[k];
                    assert!(
                        (angle[k] - ae).abs() < 1e-9,
                        "{what}: angle({}) = {} against {ae}",
                        t[k],
                        angle[k]
                    );
                    if t[k] > 0.0 {
                        assert!(
                            (friction[k] - force).abs() < 1e-9,
                            "{what}: friction({}) = {}",
                            t[k],
                            friction[k]
                        );
                    }
                }
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}

#[test]
fn a_spinning_disk_dropped_on_a_floor_leaves_with_coulombs_tangential_impulse() {
    // Dropped from h = 0.5 m spinning at ω₀ = 30 rad/s, restitution e = 0.5: the normal impulse is
    // P_n = (1 + e) m √(2 g h); the contact point slips at w = ω₀ R before the impact, and the
    // impulse that stops it is P = −m w / 3 (the slip changes by 3 P / m: P/m from the centre, R² P
    // / I from the spin). Within μ P_n it sticks (μ = 0.3): the disk leaves rolling, ẋ = P/m,
    // ω = ω₀ + R P / I; otherwise (μ = 0.1) P = −μ P_n. In flight both stay, and the height is the
    // parabola of e √(2 g h).
    let (h, w0, e) = (0.5, 30.0, 0.5);
    let v1 = (2.0 * G * h).sqrt();
    let pn = (1.0 + e) * M * v1;
    let inertia = 0.5 * M * R * R;
    for (mu, sticks) in [(0.3, true), (0.1, false)] {
        let p = if sticks { -M * w0 * R / 3.0 } else { -mu * pn };
        assert_eq!((M * w0 * R / 3.0 <= mu * pn), sticks);
        let (vx, omega) = (p / M, w0 + R * p / inertia);
        let landing = (2.0 * h / G).sqrt();
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let disk = Disk {
                    at: [0.0, R + h],
                    velocity: [0.0, 0.0],
                    spin: w0,
                    mu,
                    e,
                    normal: [0.0, 1.0],
                    platform: None,
                };
                let scene = disk.scene(formulation, integrator, 0.45);
                let what = format!("{formulation} {integrator}, μ = {mu}");
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, y, vxs, ws) = (c("t"), c("disk.x"), c("disk.y"), c("disk.vx"), c("disk.omega"));
                for k in 0..t.len() {
                    if t[k] <= landing {
                        continue;
                    }
                    let s = t[k] - landing;
                    let (xe, ye) = (vx * s, R + e * v1 * s - 0.5 * G * s * s);
                    assert!(
                        (vxs[k] - vx).abs() < 1e-9,
                        "{what}: ẋ({}) = {} against {vx}",
                        t[k],
                        vxs[k]
                    );
                    assert!(
                        (ws[k] - omega).abs() < 1e-8,
                        "{what}: ω({}) = {} against {omega}",
                        t[k],
                        ws[k]
                    );
                    assert!((x[k] - xe).abs() < 1e-9, "{what}: x({}) = {} against {xe}", t[k], x[k]);
                    assert!((y[k] - ye).abs() < 1e-9, "{what}: y({}) = {} against {ye}", t[k], y[k]);
                }
                // The impact's loss is in the balance (the impulses' work), as the friction's is.
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}

#[test]
fn a_disk_rolling_off_a_fixed_cylinder_slips_where_its_friction_reaches_mu_n() {
    // A disk (R = 0.1) on a fixed cylinder (radius 0.5, the ground's circle), released at rest at
    // φ₀ = 0.05 rad from the top. Rolling, its centre at ρ = 0.6 from the axis: energy gives
    // v² = (4/3) g ρ (cos φ₀ − cos φ); the free-body diagram, the friction (1/3) m g sin φ (up the
    // cylinder, against the roll) and the normal force m g ((7/3) cos φ − (4/3) cos φ₀). The
    // friction reaches μ N at sin φ = μ (7 cos φ − 4 cos φ₀) (found here by bisection), where the
    // disk begins to slip: from there its friction is μ N.
    let (mu, phi0, rho) = (0.3, 0.05f64, 0.6);
    let holds = |phi: f64| phi.sin() - mu * (7.0 * phi.cos() - 4.0 * phi0.cos());
    let (mut lo, mut hi) = (phi0, 1.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if holds(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let phi_slip = lo;
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let text = format!(
                "[scene]\ngravity = [0.0, {}]\n\
                 [[bodies]]\nname = \"disk\"\nmass = {M}\nshape = {{ disk = {R} }}\nposition = [{}, {}]\n\
                 [[forces]]\nname = \"roll\"\ntype = \"circle-circle\"\nbodies = [\"ground\", \"disk\"]\n\
                 at = [[0.0, 0.0], [{}, {}]]\nradii = [0.5, {R}]\nrigid = true\nfriction = {mu}\n\
                 [simulation]\nend = 1.05\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                 step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.005\n",
                -G,
                rho * phi0.sin(),
                rho * phi0.cos(),
                rho * phi0.sin(),
                rho * phi0.cos()
            );
            let scene = Scene::from_toml(&text, "cylinder").unwrap();
            let what = format!("{formulation} {integrator}");
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (x, y, friction, normal) = (c("disk.x"), c("disk.y"), c("roll.friction"), c("roll.normal"));
            let (mut rolled, mut slid) = (0, 0);
            for k in 0..x.len() {
                let phi = x[k].atan2(y[k]);
                if normal[k] <= 0.0 {
                    break;
                }
                if phi < phi_slip - 1e-3 {
                    // The output's tangent (n_y, −n_x) points down the far side: the friction, up
                    // the cylinder, is negative (1e-9 N of the 19 N load).
                    let f = -M * G * phi.sin() / 3.0;
                    let n = M * G * (7.0 / 3.0 * phi.cos() - 4.0 / 3.0 * phi0.cos());
                    assert!(
                        (friction[k] - f).abs() < 1e-9,
                        "{what}: friction at φ = {phi} is {} against {f}",
                        friction[k]
                    );
                    assert!(
                        (normal[k] - n).abs() < 1e-9,
                        "{what}: normal at φ = {phi} is {} against {n}",
                        normal[k]
                    );
                    rolled += 1;
                } else if phi > phi_slip + 1e-3 {
                    assert!(
                        (friction[k].abs() - mu * normal[k]).abs() < 1e-9,
                        "{what}: slipping at φ = {phi}, friction {} against μ N = {}",
                        friction[k],
                        mu * normal[k]
                    );
                    slid += 1;
                }
            }
            assert!(
                rolled > 10 && slid > 3,
                "{what}: {rolled} samples rolling, {slid} slipping"
            );
            // The balance closes to the integration's error: at RK4 1 ms 2.3e-9 J; at dopri5 it
            // falls with the tolerance, 2.8e-7, 5.8e-8, 1.1e-8 J at 1e-10, 1e-11, 1e-12 (of an
            // energy scale of 12 J; `dalembert simulate`, its `energy` line).
            let drift = balance_drift(&scene);
            assert!(drift < 1e-7, "{what}: E − W moved by {drift:e} J");
        }
    }
}

#[test]
fn the_shipped_draw_shot_comes_back_rolling_at_its_closed_form_speed() {
    // `scenes/draw-shot.toml`: struck at v₀ = 3 m/s with backspin ω₀ = 315 rad/s (R = 0.0286 m,
    // μ = 0.2), it slides until t* = (v₀ + ω₀ R) / (3 μ g), then rolls at (2 v₀ − ω₀ R) / 3. Its
    // position is the closed form's at every sample (dopri5 1e-10: 1e-10 m, as the floor above).
    let scene = Scene::from_path("scenes/draw-shot.toml").unwrap();
    let (v0, w0, r, mu) = (3.0, 315.0, 0.0286, 0.2);
    let t_star = (v0 + w0 * r) / (3.0 * mu * G);
    let table = run(&scene);
    let (t, x, vx) = (column(&table, "t"), column(&table, "ball.x"), column(&table, "ball.vx"));
    for k in 0..t.len() {
        let s = t[k].min(t_star);
        let xe = v0 * s - 0.5 * mu * G * s * s + (2.0 * v0 - w0 * r) / 3.0 * (t[k] - s);
        assert!((x[k] - xe).abs() < 1e-10, "x({}) = {} against {xe}", t[k], x[k]);
    }
    let last = *vx.last().unwrap();
    assert!(
        (last - (2.0 * v0 - w0 * r) / 3.0).abs() < 1e-9,
        "it rolls back at {last}"
    );
    assert!(t_star < t[t.len() - 1] && last < 0.0);
}

/// `count` points (and the first again) on the circle of `radius` about the origin, from the top
/// clockwise, as a scene's profile: `[[x, y], …]`.
fn circle_points(radius: f64, count: usize) -> String {
    let points: Vec<String> = (0..=count)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / count as f64;
            format!("[{}, {}]", radius * a.sin(), radius * a.cos())
        })
        .collect();
    format!("[{}]", points.join(", "))
}

/// The largest difference of the columns `names` of two runs (the same samples).
fn apart(a: &dalembert::output::Table, b: &dalembert::output::Table, names: &[&str]) -> f64 {
    names
        .iter()
        .map(|n| common::largest_difference(a, b, n))
        .fold(0.0, f64::max)
}

#[test]
fn friction_on_a_cam_profile_is_the_friction_on_the_circle_it_draws() {
    // The same contacts written two ways: a disk rolling off a fixed cylinder (radius 0.5) as a
    // `circle-circle` contact and as a `circle-profile` one whose profile is the cylinder's circle
    // through 400 points; a plank (1 m × 0.04 m) rocking without slipping on the cylinder as a
    // `circle-line` contact (the cylinder's circle against the plank's face, a line on the plank)
    // and as a `line-profile` one (the face against the profile). The spline is not the circle:
    // its curvature is off by O(h²) (h = 7.9e-3 m between points), so the disk's two frictionless
    // runs already differ (by 1e-7 m over its second, which amplifies a difference about 30
    // times). With friction they must differ no more than twice that, and the profile's friction
    // force must be the circle's within 1e-4 of it.
    let (mu, phi0, rho) = (0.3, 0.05f64, 0.6);
    let profile = circle_points(0.5, 400);
    let disk = |contact: &str, friction: bool| {
        let text = format!(
            "[scene]\ngravity = [0.0, {}]\n\
             [[bodies]]\nname = \"disk\"\nmass = {M}\nshape = {{ disk = {R} }}\nposition = [{}, {}]\n\
             [[forces]]\nname = \"roll\"\n{contact}rigid = true\n{}\
             [simulation]\nend = 1.05\nintegrator = \"rk4\"\nstep = 1e-3\noutput_every = 0.01\n",
            -G,
            rho * phi0.sin(),
            rho * phi0.cos(),
            if friction {
                format!("friction = {mu}\n")
            } else {
                String::new()
            }
        );
        run(&Scene::from_toml(&text, "disk").unwrap())
    };
    let centre = format!("[{}, {}]", rho * phi0.sin(), rho * phi0.cos());
    let circles = format!(
        "type = \"circle-circle\"\nbodies = [\"ground\", \"disk\"]\nat = [[0.0, 0.0], {centre}]\nradii = [0.5, {R}]\n"
    );
    let on_profile = format!(
        "type = \"circle-profile\"\nbody = \"disk\"\nradius = {R}\nprofile = {{ body = \"ground\", points = {profile} }}\n"
    );
    let position = ["disk.x", "disk.y"];
    let spline = apart(&disk(&circles, false), &disk(&on_profile, false), &position);
    let (a, b) = (disk(&circles, true), disk(&on_profile, true));
    let with_friction = apart(&a, &b, &position);
    assert!(spline < 1e-7, "the frictionless runs differ by {spline:e}");
    assert!(
        with_friction < 2.0 * spline,
        "with friction the disk on the profile is {with_friction:e} off the disk on the circle ({spline:e} without)"
    );
    // Rolling, the disk turns by the length it rolls along the spline, which is the circle's
    // within 1e-7 (5e-7 rad of 5.4 rad measured): 1e-6 of the angle.
    let (turned, angles) = (column(&a, "disk.angle"), column(&b, "disk.angle"));
    for (x, y) in turned.iter().zip(&angles) {
        assert!(
            (x - y).abs() <= 1e-6 * x.abs().max(1e-3),
            "the disk turned {y} on the profile, {x} on the circle"
        );
    }
    // The friction force (up to 3.5 N) after the first sample (where the disk starts a round-off
    // clear of the spline, and falls onto it).
    let (fa, fb) = (column(&a, "roll.friction"), column(&b, "roll.friction"));
    let force = (1..fa.len()).map(|k| (fa[k] - fb[k]).abs()).fold(0.0, f64::max);
    let largest = fa.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    assert!(
        largest > 1.0 && force < 1e-4 * largest,
        "the friction forces differ by {force:e} N of {largest} N"
    );

    // (Rocking without slipping, μ = 0.5; without friction the plank slides off.)
    let plank = |contact: &str| {
        let text = format!(
            "[scene]\ngravity = [0.0, {}]\n\
             [[bodies]]\nname = \"plank\"\nmass = 1.0\nshape = {{ rectangle = [1.0, 0.04] }}\nposition = [0.0, 0.52]\n\
             velocity = [-0.01, 0.0]\nangular_velocity = 0.5\n\
             [[forces]]\nname = \"rock\"\n{contact}rigid = true\nfriction = 0.5\n\
             [simulation]\nend = 3.0\nintegrator = \"rk4\"\nstep = 1e-3\noutput_every = 0.01\n",
            -G
        );
        let scene = Scene::from_toml(&text, "plank").unwrap();
        (run(&scene), balance_drift(&scene))
    };
    let on_line = "type = \"circle-line\"\nbody = \"ground\"\nat = [0.0, 0.0]\nradius = 0.5\nline = { body = \"plank\", point = [0.0, 0.5], normal = [0.0, -1.0] }\n";
    let on_face = format!(
        "type = \"line-profile\"\nbody = \"plank\"\nline = {{ point = [0.0, 0.5], normal = [0.0, -1.0] }}\nprofile = {{ body = \"ground\", points = {profile} }}\n"
    );
    let position = ["plank.x", "plank.y", "plank.angle"];
    let ((a, drift_line), (b, drift_face)) = (plank(on_line), plank(&on_face));
    let with_friction = apart(&a, &b, &position);
    // The spline's error moves the disk's frictionless runs 1e-7 apart; the planks, rolling over
    // it for 3 s, are 8.4e-8 apart (measured).
    assert!(
        with_friction < 3e-7,
        "with friction the plank on the profile is {with_friction:e} off the plank on the circle"
    );
    // It rocks, rolling without slipping, which does no work: T + V is kept to the integration's
    // error (RK4 1 ms: 2.9e-12 J on the circle; 1.0e-9 J on the spline, whose third derivative
    // jumps at each of the knots the contact rolls over; of 5 J).
    let angle = column(&a, "plank.angle");
    assert!(
        angle.iter().any(|a| *a < -0.05) && angle.iter().any(|a| *a > 0.05),
        "it rocks"
    );
    assert!(
        drift_line < 1e-10 && drift_face < 1e-8,
        "E − W moved by {drift_line:e}, {drift_face:e} J"
    );
}
