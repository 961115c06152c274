//! The spatial scenes of `shared/anchors` (its README defines each exactly; `spatial_scenes.py`),
//! built with `dalembert-spatial`: each body frame at the link's centre of mass with the link
//! frame's orientation, so states compare row by row with the anchors' reference
//! (`[x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz]`, angular velocity in world axes).

use dalembert_spatial::euler_parameters::from_rotation;
use dalembert_spatial::{Body, BodyRef, Joint, JointKind, Model, ModelBuilder};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// Gravitational acceleration of every anchors scene, along −z.
pub const G: f64 = 9.81;

/// `chain3d`: `n` boxes 1 m × 0.1 m × 0.1 m of 1 kg along +x, revolute joint `i` at `x = i` about
/// global `y` (even `i`) or `z` (odd `i`), at rest.
pub fn chain3d(n: usize) -> Arc<Model> {
    let (l, w, m) = (1.0, 0.1, 1.0);
    let inertia = [
        m * (w * w + w * w) / 12.0,
        m * (l * l + w * w) / 12.0,
        m * (l * l + w * w) / 12.0,
    ];
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let mut parent = BodyRef::Ground;
    for i in 0..n {
        let x = i as f64 * l;
        let link = b.body(Body::new(&format!("link{i}"), m, inertia).at([x + l / 2.0, 0.0, 0.0]));
        let axis = if i % 2 == 0 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
        b.joint(Joint::revolute(&format!("joint{i}"), parent, link, [x, 0.0, 0.0], axis));
        parent = link;
    }
    Arc::new(b.build().expect("chain3d is well formed"))
}

/// `heavytop`: 15 kg, inertia diag(0.234375, 0.46875, 0.234375), centre of mass 1 m from a ball
/// joint at the origin along body `y`, angular velocity (0, 150, −4.61538) rad/s.
pub fn heavy_top() -> Arc<Model> {
    let omega = Vector3::new(0.0, 150.0, -4.61538);
    let r = Vector3::new(0.0, 1.0, 0.0);
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let top = b.body(
        Body::new("top", 15.0, [0.234375, 0.46875, 0.234375])
            .at(r.into())
            .moving(omega.cross(&r).into(), omega.into()),
    );
    b.joint(Joint::spherical("pivot", BodyRef::Ground, top, [0.0; 3]));
    Arc::new(b.build().expect("heavytop is well formed"))
}

/// `slidercrank3d`: the IFToMM spatial slider-crank (crank, slider, rod; revolute, prismatic,
/// spherical and universal joints), with its consistent initial velocities.
pub fn slider_crank_3d() -> Arc<Model> {
    let a = Vector3::new(0.0, 0.1, 0.12);
    let (l_ab, l_bc): (f64, f64) = (0.08, 0.3);
    let bpt = a + Vector3::new(0.0, 0.0, l_ab);
    let c = Vector3::new((l_bc * l_bc - a.y * a.y - (a.z + l_ab) * (a.z + l_ab)).sqrt(), 0.0, 0.0);
    let x1 = (c - bpt) / l_bc;
    let z1 = (bpt - x1 * bpt.dot(&x1)).normalize();
    let y1 = z1.cross(&x1);
    let rod_frame = Matrix3::from_columns(&[x1, y1, z1]);
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let crank_omega = Vector3::new(6.0, 0.0, 0.0);
    let crank_com = a + Vector3::new(0.0, 0.0, l_ab / 2.0);
    let crank = b.body(
        Body::new("crank", 0.12, [1e-4, 1e-4, 1e-5])
            .at(crank_com.into())
            .moving(crank_omega.cross(&(crank_com - a)).into(), crank_omega.into()),
    );
    let slider = b.body(
        Body::new("slider", 2.0, [1e-4; 3])
            .at(c.into())
            .moving([0.24, 0.0, 0.0], [0.0; 3]),
    );
    let rod = b.body(
        Body::new("rod", 0.5, [4e-4, 4e-3, 4e-3])
            .at(((bpt + c) / 2.0).into())
            .oriented(from_rotation(&rod_frame))
            .moving([0.12, -0.24, 0.0], [2.4, -1.2, 0.0]),
    );
    b.joint(Joint::revolute("A", BodyRef::Ground, crank, a.into(), [1.0, 0.0, 0.0]));
    b.joint(Joint::new(
        "guide",
        JointKind::Prismatic,
        BodyRef::Ground,
        slider,
        c.into(),
        [1.0, 0.0, 0.0],
    ));
    b.joint(Joint::spherical("B", crank, rod, bpt.into()));
    b.joint(Joint::crossed(
        "C",
        JointKind::Universal,
        slider,
        rod,
        c.into(),
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
    ));
    Arc::new(b.build().expect("slidercrank3d is well formed"))
}

/// Largest position error (centres of mass, and the angle between computed and reference
/// orientations) and velocity error (centre-of-mass velocity, angular velocity in world axes) of a
/// state `(q, v)` of a spatial model against reference rows `[x, y, z, qw, qx, qy, qz, vx, vy, vz,
/// wx, wy, wz]`, one per body in layout order (the anchors' format).
pub fn state_errors(q: &[f64], v: &[f64], rows: &[Vec<f64>]) -> (f64, f64) {
    use dalembert_spatial::euler_parameters::{normalized, product, rotation};
    let (mut pos, mut vel) = (0.0f64, 0.0f64);
    for (i, row) in rows.iter().enumerate() {
        let p = normalized(&[q[7 * i + 3], q[7 * i + 4], q[7 * i + 5], q[7 * i + 6]]);
        for k in 0..3 {
            pos = pos.max((q[7 * i + k] - row[k]).abs());
            vel = vel.max((v[6 * i + k] - row[7 + k]).abs());
        }
        // Angle of the relative rotation p_ref⁻¹ ⊗ p: 2 atan2(|vector part|, |scalar part|).
        let reference = normalized(&[row[3], -row[4], -row[5], -row[6]]);
        let rel = product(&reference, &p);
        let angle = 2.0
            * (rel[1] * rel[1] + rel[2] * rel[2] + rel[3] * rel[3])
                .sqrt()
                .atan2(rel[0].abs());
        pos = pos.max(angle);
        let w = rotation(&p) * Vector3::new(v[6 * i + 3], v[6 * i + 4], v[6 * i + 5]);
        vel = vel.max((w - Vector3::new(row[10], row[11], row[12])).amax());
    }
    (pos, vel)
}

/// `chain3d` with `n` links as a scene file (the format of `docs/scenes.md`): bodies `link0` …
/// with `shape = { box = [1, 0.1, 0.1] }` (the anchors' inertia follows from the box), joints
/// `joint0` … as in [`chain3d`]; RK4 at 1 ms with projection for `end` seconds.
pub fn chain3d_toml(n: usize, end: f64) -> String {
    let mut s = format!(
        "# The spatial chain of shared/anchors with {n} links: boxes 1 m x 0.1 m x 0.1 m of 1 kg along +x,\n\
         # revolute joint i at x = i about global y (even i) or z (odd i), released from rest.\n\
         [scene]\nname = \"chain3d-{n}\"\ngravity = [0.0, 0.0, -{G}]\n"
    );
    for i in 0..n {
        s += &format!(
            "\n[[bodies]]\nname = \"link{i}\"\nmass = 1.0\nshape = {{ box = [1.0, 0.1, 0.1] }}\nposition = [{}, 0.0, 0.0]\n",
            i as f64 + 0.5
        );
    }
    for i in 0..n {
        let parent = if i == 0 {
            "ground".to_string()
        } else {
            format!("link{}", i - 1)
        };
        let axis = if i % 2 == 0 {
            "[0.0, 1.0, 0.0]"
        } else {
            "[0.0, 0.0, 1.0]"
        };
        s += &format!(
            "\n[[joints]]\nname = \"joint{i}\"\ntype = \"revolute\"\nbodies = [\"{parent}\", \"link{i}\"]\nat = [{}, 0.0, 0.0]\naxis = {axis}\n",
            i as f64
        );
    }
    s += &format!("\n[simulation]\nend = {end:?}\nintegrator = \"rk4\"\nstep = 1e-3\noutput_every = 0.01\n");
    s
}

/// A double pendulum (revolute about y at the origin, then about x) carrying one of each spatial
/// force element: a harmonic force in body axes, a polynomial global torque, a spring–damper with
/// an actuator, a harmonic torque about the first joint, a rotational spring–damper about the
/// second. Not an anchors scene: it exercises every force element (allocation test, agreement).
pub fn forced_double_pendulum() -> Arc<Model> {
    use dalembert_spatial::forces::ForceFrame;
    use dalembert_spatial::Force;
    use dalembert_system::TimeFunction;
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let upper = b.body(Body::new("upper", 1.0, [0.002, 0.09, 0.09]).at([0.5, 0.0, 0.0]));
    let lower = b.body(Body::new("lower", 0.5, [0.01, 0.02, 0.02]).at([1.0, 0.0, -0.3]));
    b.joint(Joint::revolute(
        "shoulder",
        BodyRef::Ground,
        upper,
        [0.0; 3],
        [0.0, 1.0, 0.0],
    ));
    b.joint(Joint::revolute("elbow", upper, lower, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]));
    let harmonic = |amplitude: f64, frequency: f64| TimeFunction::Harmonic {
        offset: 0.0,
        amplitude,
        frequency,
        phase: 0.0,
    };
    b.force(Force::PointForce {
        name: "push".into(),
        body: lower,
        point: [1.0, 0.1, -0.6],
        force: [
            harmonic(2.0, 1.0),
            TimeFunction::Constant(0.5),
            TimeFunction::Constant(0.0),
        ],
        frame: ForceFrame::Body,
    });
    b.force(Force::Torque {
        name: "twist".into(),
        body: upper,
        torque: [
            TimeFunction::Polynomial(vec![0.1, 0.2, -0.05]),
            TimeFunction::Constant(0.0),
            TimeFunction::Constant(0.3),
        ],
        frame: ForceFrame::Global,
    });
    b.force(Force::SpringDamper {
        name: "cable".into(),
        body_i: BodyRef::Ground,
        point_i: [0.0, 0.5, 1.0],
        body_j: lower,
        point_j: [1.0, 0.0, -0.6],
        stiffness: 20.0,
        damping: 0.5,
        free_length: 1.5,
        actuator: Some(harmonic(3.0, 0.5)),
    });
    b.force(Force::JointTorque {
        name: "motor".into(),
        joint: "shoulder".into(),
        torque: harmonic(4.0, 0.7),
    });
    b.force(Force::RotationalSpringDamper {
        name: "wrist-spring".into(),
        joint: "elbow".into(),
        stiffness: 5.0,
        damping: 0.1,
        free_angle: 0.2,
    });
    Arc::new(b.build().expect("the forced double pendulum is well formed"))
}
