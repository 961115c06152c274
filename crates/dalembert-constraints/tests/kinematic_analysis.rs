//! Kinematic analysis of classic mechanisms against closed forms, and structure analysis at
//! singular and redundant configurations.

use dalembert_constraints::*;
use dalembert_kinematics::{BodyId, BodyRef, Vec2};
use dalembert_system::{ConstraintError, ConstraintSet, KinematicOptions, TimeFunction};

fn b(i: usize) -> BodyRef {
    BodyRef::Body(BodyId(i))
}
const G: BodyRef = BodyRef::Ground;

/// Slider-crank: crank r about the origin, rod l, slider on the x axis; crank angle φ = φ₀ + ω t.
/// Bodies: 0 crank (centre at its middle), 1 rod (centre at its middle), 2 slider.
fn slider_crank(
    r: f64,
    l: f64,
    phi0: f64,
    omega: f64,
    extra: Option<Box<dyn Constraint>>,
) -> (ConstraintSystem, Vec<f64>) {
    let bx = r * phi0.cos();
    let by = r * phi0.sin();
    let cx = bx + (l * l - by * by).sqrt();
    let beta = (-by / l).asin();
    let q = vec![
        bx / 2.0,
        by / 2.0,
        phi0, // crank
        (bx + cx) / 2.0,
        by / 2.0,
        beta, // rod
        cx,
        0.0,
        0.0, // slider
    ];
    let o = Revolute::at("O", [G, b(0)], Vec2::zeros(), &q);
    let pin_b = Revolute::at("B", [b(0), b(1)], Vec2::new(bx, by), &q);
    let pin_c = Revolute::at("C", [b(1), b(2)], Vec2::new(cx, 0.0), &q);
    let guide = Prismatic::at("guide", [G, b(2)], Vec2::new(cx, 0.0), Vec2::x(), &q);
    let motor = JointAngle::on(
        "motor",
        &o,
        TimeFunction::Linear {
            initial: phi0,
            rate: omega,
        },
    );
    let mut all: Vec<Box<dyn Constraint>> = vec![Box::new(o), Box::new(pin_b), Box::new(pin_c), Box::new(guide)];
    // The crank motor, or another driver in its place.
    all.push(extra.unwrap_or(Box::new(motor)));
    (ConstraintSystem::new(3, all).unwrap(), q)
}

/// Positions, velocities and accelerations of the slider and the rod against
/// `x = r cos φ + √(l² − r² sin² φ)` and its derivatives over one crank turn.
///
/// Tolerance 1e-10 relative to the natural scale of each quantity (r, rω, rω² for the slider; 1,
/// ω, ω² for the rod angle), because the exact values cross zero. Newton converges to 1e-14 and the
/// linear solves are backward stable with condition ≈ 10, so round-off is ≈ 1e-14.
#[test]
fn slider_crank_matches_closed_form() {
    let (r, l, omega) = (0.5, 2.0, 6.5);
    let phi0 = 0.3;
    let (sys, mut q) = slider_crank(r, l, phi0, omega, None);
    // Start from a deliberately perturbed configuration: position analysis assembles it.
    for x in q.iter_mut() {
        *x += 0.02;
    }
    let opts = KinematicOptions::default();
    let mut worst: f64 = 0.0;
    for step in 0..=40 {
        let t = step as f64 * (2.0 * std::f64::consts::PI / omega) / 40.0;
        sys.solve_positions(t, &mut q, &opts).unwrap();
        let mut qd = vec![0.0; 9];
        sys.solve_velocities(t, &q, &mut qd, &opts).unwrap();
        let mut qdd = vec![0.0; 9];
        sys.solve_accelerations(t, &q, &qd, &mut qdd, &opts).unwrap();

        let phi = phi0 + omega * t;
        let (s, c) = phi.sin_cos();
        let root = (l * l - r * r * s * s).sqrt();
        let x = r * c + root;
        let xd = -r * s * omega - r * r * s * c * omega / root;
        let xdd = -r * c * omega * omega
            - r * r * omega * omega * (c * c - s * s) / root
            - r.powi(4) * omega * omega * s * s * c * c / root.powi(3);
        let beta = (-r * s / l).asin();
        let betad = -r * c * omega / (l * beta.cos());
        let betadd = (r * s * omega * omega + l * beta.sin() * betad * betad) / (l * beta.cos());
        let rel = |got: f64, exact: f64, scale: f64| (got - exact).abs() / scale;
        let errs = [
            rel(q[6], x, r),
            rel(qd[6], xd, r * omega),
            rel(qdd[6], xdd, r * omega * omega),
            rel(q[5], beta, 1.0),
            rel(qd[5], betad, omega),
            rel(qdd[5], betadd, omega * omega),
            // Rod centre: midpoint of B and C.
            rel(q[3], (r * c + x) / 2.0, r),
            rel(qd[4], r * c * omega / 2.0, r * omega),
        ];
        for e in errs {
            worst = worst.max(e);
        }
    }
    assert!(worst <= 1e-10, "worst relative error {worst:e}");
}

/// Four-bar: ground pivots A = (0,0), D = (2,0); crank AB = 1, coupler BC = 1.5, rocker DC = 1.
/// At cos φ = −0.3125 the coupler and rocker are collinear (|BD| = 2.5 = BC + CD): a toggle.
fn four_bar(phi: f64, toggle_branch: bool) -> (ConstraintSystem, Vec<f64>) {
    let (a, bl, c, d) = (1.0, 1.5, 1.0, 2.0);
    let pb = Vec2::new(a * phi.cos(), a * phi.sin());
    let pd = Vec2::new(d, 0.0);
    // C from the circle intersection |C − B| = bl, |C − D| = c (upper branch).
    let bd = pd - pb;
    let dist = bd.norm();
    let along = (bl * bl - c * c + dist * dist) / (2.0 * dist);
    let h = (bl * bl - along * along).max(0.0).sqrt();
    let e = bd / dist;
    let pc = pb + e * along + Vec2::new(-e.y, e.x) * if toggle_branch { h } else { -h };
    let mid = |p: Vec2, r: Vec2| (p + r) / 2.0;
    let ang = |p: Vec2, r: Vec2| (r - p).y.atan2((r - p).x);
    let (m0, m1, m2) = (mid(Vec2::zeros(), pb), mid(pb, pc), mid(pd, pc));
    let q = vec![
        m0.x,
        m0.y,
        ang(Vec2::zeros(), pb),
        m1.x,
        m1.y,
        ang(pb, pc),
        m2.x,
        m2.y,
        ang(pd, pc),
    ];
    let ja = Revolute::at("A", [G, b(0)], Vec2::zeros(), &q);
    let drive = JointAngle::on(
        "crank-drive",
        &ja,
        TimeFunction::Linear {
            initial: phi,
            rate: 1.0,
        },
    );
    let sys = ConstraintSystem::new(
        3,
        vec![
            Box::new(ja),
            Box::new(Revolute::at("B", [b(0), b(1)], pb, &q)),
            Box::new(Revolute::at("C", [b(1), b(2)], pc, &q)),
            Box::new(Revolute::at("D", [G, b(2)], pd, &q)),
            Box::new(drive),
        ],
    )
    .unwrap();
    (sys, q)
}

#[test]
fn four_bar_toggle_is_detected_and_reported() {
    let phi = (-0.3125f64).acos();
    let (sys, q) = four_bar(phi, true);
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    // The configuration is assembled (|C| at round-off) ...
    assert!(vals.c.iter().all(|c| c.abs() < 1e-12), "{:?}", vals.c);
    // ... and the driven Jacobian (9 × 9) has lost one rank.
    let s = sys.analyse_structure(&vals, 1e-9).unwrap();
    assert_eq!((s.equations, s.rank), (9, 8), "{s:?}");
    assert_eq!(s.redundant.len(), 1);
    // Velocity analysis with the crank turning: inconsistent at the toggle → a named error, no NaN.
    let mut qd = vec![0.0; 9];
    let err = sys
        .solve_velocities(0.0, &q, &mut qd, &KinematicOptions::default())
        .unwrap_err();
    match &err {
        ConstraintError::Singular { rank, involved, .. } => {
            assert_eq!(*rank, 8);
            let names: Vec<&str> = involved.iter().map(|e| e.name.as_str()).collect();
            assert!(names.contains(&"crank-drive"), "{names:?}");
        }
        other => panic!("expected a singular-Jacobian error, got {other}"),
    }
    assert!(
        qd.iter().all(|v| v.is_finite() && *v == 0.0),
        "velocities untouched on error"
    );
    assert!(err.to_string().contains("crank-drive"), "{err}");

    // Away from the toggle the same mechanism is regular.
    let (sys, q) = four_bar(phi - 0.2, true);
    sys.evaluate(0.0, &q, &[], &mut vals);
    assert!(sys.analyse_structure(&vals, 1e-9).unwrap().is_full_rank());
}

/// Parallelogram: cranks AB and DC of length 1 from A = (0,0) and D = (2,0), coupler BC; a third
/// crank EF from E = (1,0) to the coupler's midpoint is redundant. All cranks share one angle.
fn parallelogram(phi: f64, with_driver: bool) -> (ConstraintSystem, Vec<f64>) {
    let u = Vec2::new(phi.cos(), phi.sin());
    let q = vec![
        u.x / 2.0,
        u.y / 2.0,
        phi, // crank AB
        1.0 + u.x,
        u.y,
        0.0, // coupler BC (centre)
        2.0 + u.x / 2.0,
        u.y / 2.0,
        phi, // crank DC
        1.0 + u.x / 2.0,
        u.y / 2.0,
        phi, // extra crank EF
    ];
    let ja = Revolute::at("A", [G, b(0)], Vec2::zeros(), &q);
    let drive = JointAngle::on(
        "drive",
        &ja,
        TimeFunction::Linear {
            initial: phi,
            rate: 2.0,
        },
    );
    let mut joints: Vec<Box<dyn Constraint>> = vec![
        Box::new(ja),
        Box::new(Revolute::at("B", [b(0), b(1)], u, &q)),
        Box::new(Revolute::at("C", [b(1), b(2)], Vec2::new(2.0, 0.0) + u, &q)),
        Box::new(Revolute::at("D", [G, b(2)], Vec2::new(2.0, 0.0), &q)),
        Box::new(Revolute::at("E", [G, b(3)], Vec2::new(1.0, 0.0), &q)),
        Box::new(Revolute::at("F", [b(3), b(1)], Vec2::new(1.0, 0.0) + u, &q)),
    ];
    if with_driver {
        joints.push(Box::new(drive));
    }
    (ConstraintSystem::new(4, joints).unwrap(), q)
}

#[test]
fn parallelogram_with_redundant_bar_reports_dof_and_redundant_equation() {
    let phi = 1.0;
    let (sys, q) = parallelogram(phi, true);
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    assert!(vals.c.iter().all(|c| c.abs() < 1e-14));
    let s = sys.analyse_structure(&vals, 1e-9).unwrap();
    // With the driver: 13 equations, rank 12, 0 DOF; one equation redundant.
    assert_eq!(
        (s.coordinates, s.equations, s.rank, s.degrees_of_freedom),
        (12, 13, 12, 0)
    );
    assert_eq!(s.redundant.len(), 1);
    let r = &s.redundant[0];
    assert!(
        ["A", "B", "C", "D", "E", "F", "drive"].contains(&r.name.as_str()),
        "{r}"
    );
    assert!(["x", "y", "angle"].contains(&r.label));

    // Redundant but consistent: velocity and acceleration analysis succeed, and every crank turns at
    // the driven rate 2 rad/s with zero angular acceleration (closed form of the parallelogram).
    let opts = KinematicOptions::default();
    let mut qd = vec![0.0; 12];
    sys.solve_velocities(0.0, &q, &mut qd, &opts).unwrap();
    let mut qdd = vec![0.0; 12];
    sys.solve_accelerations(0.0, &q, &qd, &mut qdd, &opts).unwrap();
    for k in [2, 8, 11] {
        assert!((qd[k] - 2.0).abs() < 1e-12, "crank ω {}", qd[k]);
        assert!(qdd[k].abs() < 1e-10, "crank α {}", qdd[k]);
    }
    assert!(qd[5].abs() < 1e-12, "the coupler translates");
    // Position analysis through the redundancy from a perturbed start, later in time.
    let mut q2 = q.clone();
    q2.iter_mut().for_each(|x| *x += 0.01);
    sys.solve_positions(0.25, &mut q2, &opts).unwrap();
    for k in [2, 8, 11] {
        assert!((q2[k] - (phi + 0.5)).abs() < 1e-11, "crank angle {}", q2[k]);
    }
}

#[test]
fn parallelogram_joints_only_have_one_degree_of_freedom() {
    // 12 coordinates, 12 joint equations, rank 11 ⇒ 1 DOF and 1 redundant equation.
    let (sys, q) = parallelogram(0.7, false);
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    let s = sys.analyse_structure(&vals, 1e-9).unwrap();
    assert_eq!(
        (s.equations, s.rank, s.degrees_of_freedom, s.redundant.len()),
        (12, 11, 1, 1)
    );
}

#[test]
fn unreachable_driver_reports_violated_equations() {
    // Slider driven to x = 5 m instead of the crank: beyond r + l = 2.5 m, so unreachable.
    let push = BodyCoordinate {
        name: "push".into(),
        body: BodyId(2),
        coordinate: Coordinate::X,
        function: TimeFunction::Constant(5.0),
    };
    let (sys, mut q) = slider_crank(0.5, 2.0, 0.3, 0.0, Some(Box::new(push)));
    let err = sys
        .solve_positions(0.0, &mut q, &KinematicOptions::default())
        .unwrap_err();
    match &err {
        ConstraintError::NotConverged { violated, .. } => assert!(!violated.is_empty()),
        other => panic!("expected non-convergence, got {other}"),
    }
    assert!(q.iter().all(|x| x.is_finite()));
}
