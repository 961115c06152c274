//! The shipped six-axis arm (`scenes/arm-6.toml`, every joint driven) against the recursive
//! Newton–Euler algorithm written here from its textbook form (Luh, Walker and Paul 1980; Craig,
//! *Introduction to Robotics*, §6.5), in global components: an independent derivation of every motor
//! torque and every joint reaction, from the arm's data alone (masses, centres of mass, inertia,
//! joint points and axes, the drivers' functions, all copied from the scene file).
//!
//! The scene's numbers come from the position, velocity and acceleration analyses of the
//! constrained model and the multipliers of its constraints; the recursion below never forms a
//! constraint. Inverse dynamics solves the kinematics at each output to round-off: agreement to
//! 1e-10 of the largest torque (~100 N·m; measured 9e-14 N·m, 2026-11-24). A forward run of the
//! fully driven arm integrates the same motion (RK4 at 1 ms with projection to 1e-10): 1e-8 of the
//! largest torque (measured 6e-11 N·m).

use dalembert::{FormulationKind, Scene, SceneValue};
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use std::sync::atomic::AtomicBool;

type V = Vector3<f64>;

/// One link of the arm as written in `scenes/arm-6.toml` (all bodies start with body axes along
/// the global axes, so body-frame data are global at t = 0).
struct Link {
    mass: f64,
    /// Centre of mass at t = 0.
    com: V,
    /// Inertia about the centre of mass, global components at t = 0.
    inertia: Matrix3<f64>,
    /// The joint to the previous link (the ground for the first): point and axis at t = 0.
    joint_at: V,
    joint_axis: V,
    /// The driver: θ(t) = A (sin(ω t + φ) − sin φ), ω = 2π f (a change from the file's posture).
    amplitude: f64,
    frequency: f64,
    phase: f64,
}

fn boxed(m: f64, a: f64, b: f64, c: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&V::new(b * b + c * c, a * a + c * c, a * a + b * b)) * (m / 12.0)
}

fn arm() -> Vec<Link> {
    let link = |mass, com: [f64; 3], inertia, at: [f64; 3], axis: [f64; 3], (amplitude, frequency, phase)| Link {
        mass,
        com: V::from(com),
        inertia,
        joint_at: V::from(at),
        joint_axis: V::from(axis),
        amplitude,
        frequency,
        phase,
    };
    // A uniform cylinder about its own axis m r²/2, across m (3 r² + l²)/12.
    let (r, l) = (0.12, 0.5);
    let cylinder = Matrix3::from_diagonal(&V::new(
        10.0 * (3.0 * r * r + l * l) / 12.0,
        10.0 * (3.0 * r * r + l * l) / 12.0,
        10.0 * r * r / 2.0,
    ));
    // The tool's tensor [Jxx, Jyy, Jzz, Jxy, Jxz, Jyz] with Jxy the matrix entry.
    let tool = Matrix3::new(0.004, -0.001, 0.0005, -0.001, 0.006, 0.0002, 0.0005, 0.0002, 0.005);
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    vec![
        link(10.0, [0.0, 0.0, 0.25], cylinder, [0.0, 0.0, 0.0], z, (0.8, 0.25, 0.0)),
        link(
            6.0,
            [0.35, 0.0, 0.5],
            boxed(6.0, 0.7, 0.1, 0.12),
            [0.0, 0.0, 0.5],
            y,
            (0.4, 0.3, 0.0),
        ),
        link(
            3.0,
            [1.0, 0.0, 0.5],
            boxed(3.0, 0.6, 0.08, 0.08),
            [0.7, 0.0, 0.5],
            y,
            (0.6, 0.4, 0.5),
        ),
        link(
            0.8,
            [1.35, 0.0, 0.5],
            boxed(0.8, 0.1, 0.08, 0.08),
            [1.3, 0.0, 0.5],
            x,
            (1.0, 0.5, 0.0),
        ),
        link(
            0.5,
            [1.45, 0.0, 0.5],
            boxed(0.5, 0.1, 0.06, 0.06),
            [1.4, 0.0, 0.5],
            y,
            (0.7, 0.35, 0.0),
        ),
        link(1.5, [1.58, 0.03, 0.54], tool, [1.5, 0.0, 0.5], x, (1.2, 0.6, 0.0)),
    ]
}

/// What the recursion gives per joint at one instant: the force and the moment about the joint's
/// point that the joint's second link receives from its first, and the torque about the axis.
struct JointLoads {
    force: V,
    moment: V,
    axis: V,
    torque: f64,
}

/// Recursive Newton–Euler at time `t`: forward pass for the links' motion, backward pass for the
/// loads each joint transmits.
fn newton_euler(links: &[Link], t: f64) -> Vec<JointLoads> {
    let g = V::new(0.0, 0.0, -9.81);
    let n = links.len();
    // Previous link's state: rotation since t = 0, centre of mass, ω, α, acceleration of the centre
    // of mass, and its centre of mass at t = 0 (the ground: identity, origin, at rest).
    let (mut rot, mut x_prev, mut com0_prev) = (Matrix3::identity(), V::zeros(), V::zeros());
    let (mut w, mut alpha, mut acc) = (V::zeros(), V::zeros(), V::zeros());
    let mut state = Vec::with_capacity(n);
    for link in links {
        let w_f = 2.0 * std::f64::consts::PI * link.frequency;
        let s = w_f * t + link.phase;
        let theta = link.amplitude * (s.sin() - link.phase.sin());
        let theta_d = link.amplitude * w_f * s.cos();
        let theta_dd = -link.amplitude * w_f * w_f * s.sin();
        // The joint's point and axis are fixed in the previous link.
        let z: V = rot * link.joint_axis;
        let o: V = x_prev + rot * (link.joint_at - com0_prev);
        let a_o: V = acc + alpha.cross(&(o - x_prev)) + w.cross(&w.cross(&(o - x_prev)));
        let rel = Rotation3::from_axis_angle(&Unit::new_normalize(link.joint_axis), theta);
        let rot_i: Matrix3<f64> = rot * rel.matrix();
        let x: V = o + rot_i * (link.com - link.joint_at);
        let w_i: V = w + z * theta_d;
        let alpha_i: V = alpha + z * theta_dd + w.cross(&z) * theta_d;
        let s_vec = x - o;
        let acc_i: V = a_o + alpha_i.cross(&s_vec) + w_i.cross(&w_i.cross(&s_vec));
        state.push((o, z, x, w_i, alpha_i, acc_i, rot_i));
        (rot, x_prev, com0_prev, w, alpha, acc) = (rot_i, x, link.com, w_i, alpha_i, acc_i);
    }
    let mut loads: Vec<JointLoads> = Vec::with_capacity(n);
    let (mut f_next, mut n_next, mut o_next) = (V::zeros(), V::zeros(), V::zeros());
    for (link, &(o, z, x, w, alpha, acc, rot)) in links.iter().zip(&state).rev() {
        let j = rot * link.inertia * rot.transpose();
        let f: V = (acc - g) * link.mass + f_next;
        let m: V = j * alpha
            + w.cross(&(j * w))
            + (x - o).cross(&((acc - g) * link.mass))
            + n_next
            + (o_next - o).cross(&f_next);
        loads.push(JointLoads {
            force: f,
            moment: m,
            axis: z,
            torque: z.dot(&m),
        });
        (f_next, n_next, o_next) = (f, m, o);
    }
    loads.reverse();
    loads
}

const JOINTS: [&str; 6] = ["waist", "shoulder", "elbow", "wrist-roll", "wrist-pitch", "flange"];
const MOTORS: [&str; 6] = ["m1", "m2", "m3", "m4", "m5", "m6"];

fn scene() -> Scene {
    Scene::from_path(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/arm-6.toml")).unwrap()
}

/// Largest deviation of a table's efforts and reactions from the recursion, and the largest torque.
fn deviation(table: &dalembert::output::Table, links: &[Link]) -> (f64, f64, f64) {
    let col = |c: &str| table.column(c).unwrap();
    let t = col("t");
    let (mut torque_dev, mut reaction_dev, mut largest) = (0.0f64, 0.0f64, 0.0f64);
    for k in 0..t.len() {
        let loads = newton_euler(links, t[k]);
        for (i, l) in loads.iter().enumerate() {
            largest = largest.max(l.torque.abs());
            torque_dev = torque_dev.max((col(&format!("{}.effort", MOTORS[i]))[k] - l.torque).abs());
            // The joint's reaction is on its first link from its second: the opposite of what the
            // second receives; its moment leaves out the motor's torque about the axis (the
            // driver's own multiplier).
            let j = JOINTS[i];
            let force = -l.force;
            let moment = -(l.moment - l.axis * l.torque);
            for (c, v) in ["fx", "fy", "fz"]
                .iter()
                .zip(force.iter())
                .chain(["mx", "my", "mz"].iter().zip(moment.iter()))
            {
                reaction_dev = reaction_dev.max((col(&format!("{j}.{c}"))[k] - v).abs());
            }
        }
    }
    (torque_dev, reaction_dev, largest)
}

#[test]
fn arm_inverse_dynamics_is_the_recursive_newton_euler_algorithm() {
    let links = arm();
    let scene = scene();
    let report = scene.check().unwrap();
    assert_eq!(report.degrees_of_freedom, 0, "every joint is driven");
    let (table, outcome) = scene.inverse_table(4.0, 0.01);
    outcome.unwrap();
    assert_eq!(table.rows(), 401);
    let (torque_dev, reaction_dev, largest) = deviation(&table, &links);
    eprintln!("inverse: torques {torque_dev:e}, reactions {reaction_dev:e}, largest torque {largest}");
    assert!(largest > 50.0, "the shoulder carries the arm: {largest} N·m");
    assert!(torque_dev < 1e-10 * largest, "motor torques off by {torque_dev:e} N·m");
    assert!(reaction_dev < 1e-10 * largest, "reactions off by {reaction_dev:e}");
}

#[test]
fn every_formulation_runs_the_driven_arm_to_the_same_loads() {
    // With every joint driven the forward run is kinematic; its output rows carry the same
    // efforts and reactions, from each formulation's own multipliers.
    let links = arm();
    for f in FormulationKind::ALL {
        let s = scene()
            .with_values(&[
                ("simulation.end", 1.0.into()),
                ("simulation.formulation", SceneValue::Text(f.name().into())),
            ])
            .unwrap();
        let rec = s.record(&AtomicBool::new(false));
        rec.outcome.unwrap();
        let (torque_dev, reaction_dev, largest) = deviation(&rec.table, &links);
        eprintln!("{}: torques {torque_dev:e}, reactions {reaction_dev:e}", f.name());
        assert!(
            torque_dev < 1e-8 * largest,
            "{}: motor torques off by {torque_dev:e}",
            f.name()
        );
        assert!(
            reaction_dev < 1e-8 * largest,
            "{}: reactions off by {reaction_dev:e}",
            f.name()
        );
    }
}
