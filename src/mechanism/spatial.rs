//! Spatial bodies as a [`ModelKind`]: centre of mass, Euler parameters and velocities per body,
//! a force and a moment per joint, an effort per driver.

use super::{ColumnWriter, ModelKind};
use dalembert_integrators::Sample;
use dalembert_spatial::frame::Frame;
use dalembert_spatial::joint_values::unwrap_angle;
use dalembert_spatial::{JointValueKind, Model, Reaction};
use dalembert_system::MultibodySystem;
use std::any::Any;
use std::sync::Arc;

/// The columns of a spatial body: centre of mass, Euler parameters, centre-of-mass velocity and
/// angular velocity (global components).
pub const SPATIAL_BODY_COLUMNS: [&str; 13] = [
    "x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz",
];

/// The columns of a spatial joint: force and moment (about the joint's point) that its second body
/// exerts on its first, global components.
pub const SPATIAL_JOINT_COLUMNS: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];

/// The columns of a compliant contact (`docs/contact.md`, "Output"): its gap, normal force, the
/// force on its body (global) and the point where it acts.
pub const SPATIAL_CONTACT_COLUMNS: [&str; 8] = ["gap", "normal", "fx", "fy", "fz", "px", "py", "pz"];

/// The joint-space columns of a revolute or prismatic joint, after all the bodies' columns: its
/// angle (continuous over a run) or displacement, 0 in the file's configuration, and its rate
/// ([`dalembert_spatial::joint_values`]).
pub const SPATIAL_JOINT_VALUE_COLUMNS: [&str; 3] = ["q", "qd", "qdd"];

impl ModelKind for Model {
    fn system(&self) -> &dyn MultibodySystem {
        self
    }

    fn shared_system(self: Arc<Self>) -> Arc<dyn MultibodySystem> {
        self
    }

    fn dimension(&self) -> usize {
        3
    }

    fn constraint_names(&self) -> Vec<String> {
        self.joint_names()
            .chain(self.driver_names())
            .chain(self.coupling_names())
            .map(String::from)
            .collect()
    }

    fn driver_names(&self) -> Vec<String> {
        Model::driver_names(self).map(String::from).collect()
    }

    fn nonconservative_force_names(&self) -> Vec<String> {
        Model::nonconservative_force_names(self).map(String::from).collect()
    }

    fn position_columns(&self) -> &'static [&'static str] {
        &SPATIAL_BODY_COLUMNS[..3]
    }

    fn columns(self: Arc<Self>) -> Box<dyn ColumnWriter> {
        let joints = self.joint_names().count();
        Box::new(SpatialColumns {
            reactions: vec![
                Reaction {
                    force: Default::default(),
                    moment: Default::default(),
                    point: Default::default(),
                    axes: Default::default(),
                };
                joints
            ],
            drivers: Model::driver_names(&self).count(),
            joint_values: vec![(0.0, 0.0); self.joint_value_names().count()],
            joint_accelerations: vec![0.0; self.joint_value_names().count()],
            previous: vec![(0.0, 0.0, 0.0); self.joint_value_names().count()],
            previous_t: f64::NAN,
            contacts: vec![Default::default(); self.contact_names().count()],
            rigid: vec![Default::default(); self.rigid_contact_count()],
            model: self,
        })
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn into_any(self: Arc<Self>) -> Arc<dyn Any + Send + Sync> {
        self
    }
}

/// The columns of a spatial model and the scratch space of its reactions.
#[derive(Debug, Clone)]
struct SpatialColumns {
    model: Arc<Model>,
    reactions: Vec<Reaction>,
    drivers: usize,
    /// Scratch space of the joint values (`<joint>.q`, `<joint>.qd`).
    joint_values: Vec<(f64, f64)>,
    /// And of their accelerations (`<joint>.qdd`).
    joint_accelerations: Vec<f64>,
    /// Each joint value, rate and acceleration of the previous row (0 before the first), and its
    /// time (NaN before the first): an angle is unwrapped against its value carried from there
    /// ([`carried_angle`]), so that it is continuous over a run.
    previous: Vec<(f64, f64, f64)>,
    previous_t: f64,
    /// Scratch space of the compliant contacts' resultants.
    contacts: Vec<dalembert_system::ContactResultant<3>>,
    /// And of the rigid contacts' (their normal forces the run's limit forces).
    rigid: Vec<dalembert_system::ContactResultant<3>>,
}

impl ColumnWriter for SpatialColumns {
    fn body_columns(&self) -> Vec<String> {
        let bodies = self.model.bodies().iter();
        let mut names: Vec<String> = bodies
            .flat_map(|b| SPATIAL_BODY_COLUMNS.iter().map(move |c| format!("{}.{c}", b.name)))
            .collect();
        let joints = self.model.joint_value_names();
        names.extend(joints.flat_map(|(j, _)| SPATIAL_JOINT_VALUE_COLUMNS.map(|c| format!("{j}.{c}"))));
        names
    }

    fn reaction_columns(&self) -> Vec<String> {
        let joints = self.model.joint_names();
        let mut names: Vec<String> = joints
            .flat_map(|j| SPATIAL_JOINT_COLUMNS.iter().map(move |c| format!("{j}.{c}")))
            .collect();
        names.extend(self.model.driver_names().map(|d| format!("{d}.effort")));
        // Couplings: the torque or force each applies along its follower joint
        // (`docs/couplings.md`).
        names.extend(self.model.coupling_names().map(|c| format!("{c}.effort")));
        // Joint limits: the stop's torque or force on the second body along the joint
        // (`docs/limits.md`); joint friction: its torque or force likewise (`docs/friction.md`).
        // Both are in the joint's reaction columns too.
        // A rigid contact's friction cone: one column, the size of its force in the tangent
        // plane (the force itself is in the contact's fx, fy, fz).
        names.extend(
            (self.model.friction_specs().iter().enumerate())
                .filter(|(k, f)| f.cone.is_none_or(|p| p > *k))
                .map(|(_, f)| format!("{}.friction", f.name)),
        );
        // Rigid contacts: the gap (m), the normal force on the body (N), that force (global) and
        // the contact point, as a compliant contact's columns.
        for l in self.model.limit_specs() {
            if l.element == "contact" {
                names.extend(SPATIAL_CONTACT_COLUMNS.map(|k| format!("{}.{k}", l.name)));
            } else {
                names.push(format!("{}.limit", l.name));
            }
        }
        // Compliant contacts: gap, normal force, force on the body and where it acts.
        for c in self.model.contact_names() {
            names.extend(SPATIAL_CONTACT_COLUMNS.map(|k| format!("{c}.{k}")));
        }
        names
    }

    fn push(&mut self, s: &Sample<'_>, row: &mut Vec<f64>) {
        for i in 0..self.model.bodies().len() {
            let f = Frame::of(i, s.q, s.qd);
            row.extend_from_slice(&s.q[7 * i..7 * i + 7]);
            row.extend(f.v.iter().chain(f.w.iter()));
        }
        self.model.joint_values_into(s.q, s.qd, &mut self.joint_values);
        self.model
            .joint_accelerations_into(s.q, s.qd, s.qdd, &mut self.joint_accelerations);
        let kinds = self.model.joint_value_names().map(|(_, k)| k);
        let values = self.joint_values.iter_mut().zip(&self.joint_accelerations);
        let h = s.t - self.previous_t;
        for (((value, rate), &acceleration), (last, kind)) in values.zip(self.previous.iter_mut().zip(kinds)) {
            if kind == JointValueKind::Angle {
                *value = unwrap_angle(carried_angle(*last, (*rate, acceleration), h), *value);
            }
            *last = (*value, *rate, acceleration);
            row.extend([*value, *rate, acceleration]);
        }
        self.previous_t = s.t;
        self.model.reactions_into(s.t, s.q, s.lambda, &mut self.reactions);
        self.model
            .add_joint_forces_into(s.q, s.limit, s.friction, &mut self.reactions);
        for r in &self.reactions {
            row.extend(r.force.iter().chain(r.moment.iter()));
        }
        let first = s.lambda.len() - self.drivers;
        row.extend(s.lambda[first..].iter().map(|l| -l));
        row.extend(self.model.coupling_efforts(s.lambda));
        let specs = self.model.friction_specs();
        for (k, f) in specs.iter().enumerate() {
            let force = |k: usize| s.friction.get(k).copied().unwrap_or(0.0);
            match f.cone {
                None => row.push(force(k)),
                Some(p) if p > k => row.push(force(k).hypot(force(p))),
                Some(_) => {}
            }
        }
        (self.model).rigid_contact_resultants_into(s.q, (s.limit, s.friction), &mut self.rigid);
        let mut rigid = self.rigid.iter();
        for (k, l) in self.model.limit_specs().iter().enumerate() {
            let force = s.limit.get(k).copied().unwrap_or(0.0);
            if l.element == "contact" {
                let c = rigid.next().copied().unwrap_or_default();
                row.extend([c.gap, force]);
                row.extend(c.force.iter().chain(&c.point));
            } else {
                row.push(force);
            }
        }
        self.model.contact_resultants_into(s.q, s.qd, &mut self.contacts);
        for c in &self.contacts {
            row.extend([c.gap, c.normal]);
            row.extend(c.force.iter().chain(&c.point));
        }
    }

    fn boxed_clone(&self) -> Box<dyn ColumnWriter> {
        Box::new(self.clone())
    }
}

/// The angle of the last row `(θ₀, θ̇₀, θ̈₀)` carried `h` on, to the row whose rate and
/// acceleration are `(θ̇₁, θ̈₁)`: `θ₀ + h (θ̇₀ + θ̇₁)/2 + h² (θ̈₀ − θ̈₁)/12`, the integral of the
/// rate's cubic through both rows (`docs/scenes.md`, "Joint values"). The row's angle, read
/// within a turn, is taken on the turn nearest it, so a joint turning more than half a turn
/// between rows keeps counting. `θ₀` alone where there is no step forward (the first row, a run
/// moved back) or a value is not finite.
fn carried_angle((angle, rate, acceleration): (f64, f64, f64), (rate_1, acceleration_1): (f64, f64), h: f64) -> f64 {
    let carried = angle + 0.5 * h * (rate + rate_1) + h * h / 12.0 * (acceleration - acceleration_1);
    if h > 0.0 && carried.is_finite() {
        carried
    } else {
        angle
    }
}
