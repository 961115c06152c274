//! Planar bodies as a [`ModelKind`]: `x, y, angle` per body, reactions `fx, fy` (and a torque
//! where the joint carries one), an effort per driver.

use super::{ColumnWriter, ModelKind};
use dalembert_constraints::{ConstraintRole, Model, Reaction};
use dalembert_integrators::Sample;
use dalembert_system::{ConstraintSet as _, ConstraintValues, MultibodySystem};
use std::any::Any;
use std::sync::Arc;

/// The columns of a planar body: reference point, angle (continuous, never wrapped) and their
/// rates.
pub const PLANAR_BODY_COLUMNS: [&str; 6] = ["x", "y", "angle", "vx", "vy", "omega"];

/// The columns of a planar compliant contact (`docs/contact.md`, "Output"): its gap, normal
/// force, the force on its body (global) and the point where it acts.
pub const PLANAR_CONTACT_COLUMNS: [&str; 6] = ["gap", "normal", "fx", "fy", "px", "py"];

impl ModelKind for Model {
    fn system(&self) -> &dyn MultibodySystem {
        self
    }

    fn shared_system(self: Arc<Self>) -> Arc<dyn MultibodySystem> {
        self
    }

    fn dimension(&self) -> usize {
        2
    }

    fn constraint_names(&self) -> Vec<String> {
        self.constraints()
            .constraints()
            .iter()
            .map(|c| c.name().to_string())
            .collect()
    }

    fn driver_names(&self) -> Vec<String> {
        self.constraints()
            .constraints()
            .iter()
            .filter(|c| c.role() == ConstraintRole::Driver)
            .map(|c| c.name().to_string())
            .collect()
    }

    fn nonconservative_force_names(&self) -> Vec<String> {
        self.forces()
            .iter()
            .filter(|f| !f.is_conservative())
            .map(|f| f.name().to_string())
            .collect()
    }

    fn position_columns(&self) -> &'static [&'static str] {
        &PLANAR_BODY_COLUMNS[..3]
    }

    fn columns(self: Arc<Self>) -> Box<dyn ColumnWriter> {
        let sys = self.constraints();
        let roles: Vec<ConstraintRole> = sys.constraints().iter().map(|c| c.role()).collect();
        // The compliant contacts: the force elements that have a gap (whatever the state).
        let q = vec![0.0; 3 * self.bodies().len()];
        let contacts = (self.forces().iter().enumerate())
            .filter(|(_, f)| f.contact_gap(self.bodies(), &q).is_some())
            .map(|(k, _)| k)
            .collect();
        Box::new(PlanarColumns {
            values: sys.values(),
            reactions: vec![Reaction::default(); roles.len()],
            roles,
            contacts,
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

/// The columns of a planar model and the scratch space of its reactions.
#[derive(Debug, Clone)]
struct PlanarColumns {
    model: Arc<Model>,
    roles: Vec<ConstraintRole>,
    values: ConstraintValues,
    reactions: Vec<Reaction>,
    /// The force elements that are compliant contacts (`docs/contact.md`, "Output").
    contacts: Vec<usize>,
}

impl ColumnWriter for PlanarColumns {
    fn body_columns(&self) -> Vec<String> {
        self.model
            .bodies()
            .iter()
            .flat_map(|b| PLANAR_BODY_COLUMNS.iter().map(move |c| format!("{}.{c}", b.name)))
            .collect()
    }

    fn reaction_columns(&self) -> Vec<String> {
        let mut names = Vec::new();
        let sys = self.model.constraints();
        for (c, role) in sys.constraints().iter().zip(&self.roles) {
            match role {
                ConstraintRole::Joint { carries_torque } => {
                    names.push(format!("{}.fx", c.name()));
                    names.push(format!("{}.fy", c.name()));
                    if *carries_torque {
                        names.push(format!("{}.torque", c.name()));
                    }
                }
                ConstraintRole::Driver => names.push(format!("{}.effort", c.name())),
            }
        }
        // Joint friction: its force (N) or torque (N·m) on the second body, also in the joint's
        // reaction above (`docs/friction.md`).
        names.extend(self.model.frictions().iter().map(|f| format!("{}.friction", f.name())));
        // Joint limits: the joint's coordinate (zero in the file's configuration) and the
        // limit's force or torque on the second body while it rests on a bound, also in the
        // joint's reaction (`docs/limits.md`).
        for l in self.model.limits() {
            names.push(format!("{}.q", l.name()));
            names.push(format!("{}.limit", l.name()));
        }
        // Rigid contacts: the gap (m) and the normal force on the body (N); with friction, the
        // friction force on the circle along the tangent (n_y, −n_x) (`docs/limits.md`).
        for c in self.model.rigid_contacts() {
            names.push(format!("{}.gap", c.name));
            names.push(format!("{}.normal", c.name));
            if c.friction.is_some() {
                names.push(format!("{}.friction", c.name));
            }
        }
        // Compliant contacts: gap, normal force, force on the body and where it acts.
        for &k in &self.contacts {
            let name = self.model.forces()[k].name();
            names.extend(PLANAR_CONTACT_COLUMNS.map(|c| format!("{name}.{c}")));
        }
        names
    }

    fn push(&mut self, s: &Sample<'_>, row: &mut Vec<f64>) {
        let sys = self.model.constraints();
        sys.evaluate(s.t, s.q, s.qd, &mut self.values);
        sys.reactions(s.q, &self.values, s.lambda, &mut self.reactions);
        for (f, force) in self.model.frictions().iter().zip(s.friction) {
            f.add_to_reaction(s.q, *force, &mut self.reactions[f.constraint]);
        }
        for (l, force) in self.model.limits().iter().zip(s.limit) {
            l.add_to_reaction(s.q, *force, &mut self.reactions[l.constraint]);
        }
        for i in 0..s.q.len() / 3 {
            row.extend_from_slice(&s.q[3 * i..3 * i + 3]);
            row.extend_from_slice(&s.qd[3 * i..3 * i + 3]);
        }
        for (r, role) in self.reactions.iter().zip(&self.roles) {
            match role {
                ConstraintRole::Joint { carries_torque } => {
                    row.extend_from_slice(&[r.force.x, r.force.y]);
                    if *carries_torque {
                        row.push(r.torque);
                    }
                }
                ConstraintRole::Driver => row.push(r.effort.unwrap_or(f64::NAN)),
            }
        }
        let frictions = self.model.frictions().len();
        let elements = frictions + self.model.contact_frictions().len();
        if s.friction.len() == elements {
            row.extend_from_slice(&s.friction[..frictions]);
        } else {
            row.extend(std::iter::repeat_n(0.0, frictions));
        }
        for (k, l) in self.model.limits().iter().enumerate() {
            row.push(l.coordinate(s.q));
            row.push(s.limit.get(k).copied().unwrap_or(0.0));
        }
        let first = self.model.limits().len();
        let mut contact_friction = s.friction.iter().skip(frictions);
        for (k, c) in self.model.rigid_contacts().iter().enumerate() {
            row.push(c.gap(s.q));
            row.push(s.limit.get(first + k).copied().unwrap_or(0.0));
            if c.friction.is_some() {
                row.push(contact_friction.next().copied().unwrap_or(0.0));
            }
        }
        for &k in &self.contacts {
            let f = &self.model.forces()[k];
            let r = f.contact_resultant(self.model.bodies(), s.q, s.qd).unwrap_or_default();
            row.extend([r.gap, r.normal]);
            row.extend(r.force.iter().chain(&r.point));
        }
    }

    fn boxed_clone(&self) -> Box<dyn ColumnWriter> {
        Box::new(self.clone())
    }
}
