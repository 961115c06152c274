//! Random valid planar mechanisms from a compact specification (so that property tests can shrink
//! a failing case to a smaller mechanism by dropping bodies, loops, springs or drivers).
//!
//! Every joint is created *at the current configuration* (its points coincide where the bodies
//! are), so the configuration is consistent by construction; velocities are random and then made
//! consistent by velocity analysis. A loop or driver is kept only if the Jacobian stays full rank
//! and well conditioned and at least one degree of freedom remains.

use crate::mechanisms::{Mechanism, G};
use dalembert_constraints::{
    Constraint, ConstraintSystem, Distance, JointAngle, Model, PointOnLine, Prismatic, Revolute,
};
use dalembert_kinematics::{Body, BodyId, BodyRef, ForceElement, Gravity, SpringDamper, Vec2};
use dalembert_system::ConstraintSet as _;
use dalembert_system::KinematicOptions;
use dalembert_system::TimeFunction;
use std::sync::Arc;

/// One body of a tree, attached to an earlier body or the ground.
#[derive(Debug, Clone, PartialEq)]
pub struct BodySpec {
    /// Parent index modulo the bodies so far plus one (0 = ground).
    pub parent: usize,
    /// 0: revolute, 1: prismatic, 2: distance (massless rod of length `length / 2` plus a pin-free body).
    pub joint: u8,
    /// Length of the body (m), 0.3–2.
    pub length: f64,
    /// Absolute angle (rad).
    pub angle: f64,
    /// Mass (kg); the mass ratio across a mechanism can be large.
    pub mass: f64,
    /// Inertia as a fraction of `m L² / 12` (0.2–2).
    pub inertia_factor: f64,
    /// Slide offset along a prismatic axis (m).
    pub slide: f64,
}

/// A loop-closing joint between two existing bodies (indices modulo bodies + 1, 0 = ground).
#[derive(Debug, Clone, PartialEq)]
pub struct LoopSpec {
    /// First body.
    pub a: usize,
    /// Second body.
    pub b: usize,
    /// 0: revolute at a point between them, 1: distance between their tips, 2: point-on-line.
    pub kind: u8,
    /// Where along the segment between the two bodies' tips the joint point lies (0–1).
    pub at: f64,
}

/// A spring–damper between two bodies' tips.
#[derive(Debug, Clone, PartialEq)]
pub struct SpringSpec {
    /// First body (mod bodies + 1).
    pub a: usize,
    /// Second body.
    pub b: usize,
    /// Stiffness (N/m).
    pub stiffness: f64,
    /// Damping (N·s/m).
    pub damping: f64,
}

/// A whole mechanism.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// The tree, in order.
    pub bodies: Vec<BodySpec>,
    /// Loop-closing joints.
    pub loops: Vec<LoopSpec>,
    /// Springs.
    pub springs: Vec<SpringSpec>,
    /// Revolute joints (tree index mod count) driven at a constant rate.
    pub drivers: Vec<usize>,
    /// Velocity seed values (cycled over the coordinates before velocity analysis).
    pub velocities: Vec<f64>,
}

type Shared = Arc<dyn Constraint>;

fn body_ref(i: usize) -> BodyRef {
    if i == 0 {
        BodyRef::Ground
    } else {
        BodyRef::Body(BodyId(i - 1))
    }
}

fn system(n_bodies: usize, cons: &[Shared]) -> Option<ConstraintSystem> {
    ConstraintSystem::new(
        n_bodies,
        cons.iter()
            .map(|c| Box::new(c.clone()) as Box<dyn Constraint>)
            .collect(),
    )
    .ok()
}

/// True when `C_q` has full row rank, its smallest singular value is at least 1e-4 of the largest,
/// and at least one degree of freedom remains.
fn acceptable(n_bodies: usize, cons: &[Shared], q: &[f64]) -> bool {
    let Some(sys) = system(n_bodies, cons) else {
        return false;
    };
    let mut vals = sys.values();
    sys.evaluate(0.0, q, &[], &mut vals);
    let (m, n) = (sys.num_equations(), sys.num_coordinates());
    if m == 0 {
        return true;
    }
    if m >= n {
        return false;
    }
    let Ok(s) = sys.jacobian_dense(&vals).singular_values() else {
        return false;
    };
    let largest = s.iter().cloned().fold(0.0, f64::max);
    let smallest = s.iter().cloned().fold(f64::INFINITY, f64::min);
    s.len() == m && smallest >= 1e-4 * largest
}

/// Builds the mechanism of `spec`; `None` if nothing valid results (no bodies).
pub fn build(spec: &Spec) -> Option<Mechanism> {
    if spec.bodies.is_empty() {
        return None;
    }
    let mut bodies = Vec::new();
    let mut q: Vec<f64> = Vec::new();
    // Tip (global) of every body; index 0 is a ground point.
    let mut tips = vec![Vec2::new(0.0, 0.0)];
    let mut cons: Vec<Shared> = Vec::new();
    let mut revolutes: Vec<Revolute> = Vec::new();
    for (k, bs) in spec.bodies.iter().enumerate() {
        let parent = bs.parent % (k + 1);
        let attach = if parent == 0 {
            Vec2::new(0.7 * k as f64, 0.0)
        } else {
            tips[parent]
        };
        let dir = Vec2::new(bs.angle.cos(), bs.angle.sin());
        let base = if bs.joint == 1 {
            attach + dir * bs.slide
        } else if bs.joint == 2 {
            attach + dir * (bs.length / 2.0)
        } else {
            attach
        };
        let centre = base + dir * (bs.length / 2.0);
        q.extend_from_slice(&[centre.x, centre.y, bs.angle]);
        tips.push(base + dir * bs.length);
        bodies.push(
            Body::new(
                format!("b{k}"),
                bs.mass,
                bs.inertia_factor * bs.mass * bs.length * bs.length / 12.0,
            )
            .ok()?,
        );
        let pair = [body_ref(parent), body_ref(k + 1)];
        let name = format!("j{k}");
        let c: Shared = match bs.joint {
            1 => Arc::new(Prismatic::at(name, pair, attach, dir, &q)),
            2 => Arc::new(Distance::between(name, pair, attach, base, &q)),
            _ => {
                let r = Revolute::at(name, pair, attach, &q);
                revolutes.push(r.clone());
                Arc::new(r)
            }
        };
        cons.push(c);
    }
    let nb = bodies.len();
    for (k, l) in spec.loops.iter().enumerate() {
        let (a, b) = (l.a % (nb + 1), l.b % (nb + 1));
        if a == b {
            continue;
        }
        let (pa, pb) = (tips[a], tips[b]);
        let p = pa + (pb - pa) * l.at;
        let pair = [body_ref(a), body_ref(b)];
        let name = format!("loop{k}");
        let c: Shared = match l.kind {
            1 if (pb - pa).norm() > 0.2 => Arc::new(Distance::between(name, pair, pa, pb, &q)),
            2 => Arc::new(PointOnLine::at(name, pair, p, Vec2::new(1.0, 0.3), &q)),
            _ => Arc::new(Revolute::at(name, pair, p, &q)),
        };
        cons.push(c);
        if !acceptable(nb, &cons, &q) {
            cons.pop();
        }
    }
    for (k, &d) in spec.drivers.iter().enumerate() {
        if revolutes.is_empty() {
            break;
        }
        let r = &revolutes[d % revolutes.len()];
        let [a, b] = r.bodies;
        let now = dalembert_kinematics::BodyState::of(b, &q, &[]).angle
            - dalembert_kinematics::BodyState::of(a, &q, &[]).angle;
        cons.push(Arc::new(JointAngle::on(
            format!("drive{k}"),
            r,
            TimeFunction::Linear {
                initial: now,
                rate: 0.5 + k as f64,
            },
        )));
        if !acceptable(nb, &cons, &q) {
            cons.pop();
        }
    }
    if !acceptable(nb, &cons, &q) {
        return None;
    }
    let mut forces: Vec<Box<dyn ForceElement>> = vec![Box::new(Gravity::new(Vec2::new(0.0, -G)))];
    for (k, s) in spec.springs.iter().enumerate() {
        let (a, b) = (s.a % (nb + 1), s.b % (nb + 1));
        if a == b {
            continue;
        }
        let pts = (
            dalembert_constraints::joints::local_point_of(body_ref(a), &q, tips[a]),
            dalembert_constraints::joints::local_point_of(body_ref(b), &q, tips[b]),
        );
        forces.push(Box::new(SpringDamper {
            name: format!("spring{k}"),
            bodies: (body_ref(a), body_ref(b)),
            points: pts,
            stiffness: s.stiffness,
            damping: s.damping,
            free_length: 0.8 * (tips[b] - tips[a]).norm(),
            actuator: None,
        }));
    }
    let model = Model::new(
        bodies,
        forces,
        cons.iter()
            .map(|c| Box::new(c.clone()) as Box<dyn Constraint>)
            .collect(),
    )
    .ok()?;
    let mut qd: Vec<f64> = (0..q.len())
        .map(|i| {
            spec.velocities
                .get(i % spec.velocities.len().max(1))
                .copied()
                .unwrap_or(0.0)
        })
        .collect();
    model
        .constraints()
        .solve_velocities(0.0, &q, &mut qd, &KinematicOptions::default())
        .ok()?;
    Some(Mechanism {
        model: Arc::new(model),
        q,
        qd,
    })
}
