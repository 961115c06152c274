//! A complete planar multibody model: bodies, applied forces and constraints, and its
//! implementation of the system seam ([`MultibodySystem`]).

use crate::system::PLANAR_LABELS;
use crate::{Constraint, ConstraintSystem, Friction, Limit, RigidContact};
use dalembert_kinematics::{Body, BodyState, ForceElement, MassMatrix};
use dalembert_system::{BlockDiagonal, DynamicsError, Layout, MultibodySystem};
use dalembert_system::{ConstraintError, ConstraintSet};
use dalembert_system::{JointFriction, JointLimit, PowerScratch, SlipRow};

/// Bodies, applied force elements and the assembled constraint system of one mechanism.
#[derive(Debug)]
pub struct Model {
    bodies: Vec<Body>,
    forces: Vec<Box<dyn ForceElement>>,
    constraints: ConstraintSystem,
    layout: Layout,
    mass_is_constant: bool,
    frictions: Vec<Friction>,
    /// The joints' friction elements, then the rigid contacts' with friction.
    friction_specs: Vec<JointFriction>,
    /// The rigid contacts with friction, in the order of their elements.
    contact_frictions: Vec<usize>,
    limits: Vec<Limit>,
    rigid_contacts: Vec<RigidContact>,
    /// The joint limits' specs, then the rigid contacts'.
    limit_specs: Vec<JointLimit>,
}

impl Model {
    /// Validates and assembles a model. Errors name the element at fault.
    pub fn new(
        bodies: Vec<Body>,
        forces: Vec<Box<dyn ForceElement>>,
        constraints: Vec<Box<dyn Constraint>>,
    ) -> Result<Self, ConstraintError> {
        for f in &forces {
            f.validate(bodies.len())?;
        }
        let constraints = ConstraintSystem::new(bodies.len(), constraints)?;
        let layout = Layout::new(bodies.iter().map(|b| (b.name.as_str(), PLANAR_LABELS, PLANAR_LABELS)));
        let mass_is_constant = bodies
            .iter()
            .all(|b| b.center_of_mass == dalembert_kinematics::Vec2::zeros());
        Ok(Model {
            bodies,
            forces,
            constraints,
            layout,
            mass_is_constant,
            frictions: Vec::new(),
            friction_specs: Vec::new(),
            contact_frictions: Vec::new(),
            limits: Vec::new(),
            rigid_contacts: Vec::new(),
            limit_specs: Vec::new(),
        })
    }

    /// The model with friction in some of its revolute and prismatic joints
    /// (`docs/friction.md`). Errors name the joint.
    pub fn with_frictions(mut self, frictions: Vec<Friction>) -> Result<Self, ConstraintError> {
        for f in &frictions {
            f.validate()?;
            if f.constraint >= self.constraints.constraints().len()
                || self.constraints.constraints()[f.constraint].name() != f.name()
            {
                return Err(dalembert_system::ModelError::InvalidParameter {
                    element: format!("joint '{}'", f.name()),
                    what: "friction refers to a joint the model does not hold".to_string(),
                }
                .into());
            }
        }
        self.frictions = frictions;
        self.friction_specs = self.friction_elements();
        Ok(self)
    }

    /// The joints' friction elements, then each rigid contact's with friction (loaded by the
    /// contact's force, the limit after the joint limits).
    fn friction_elements(&mut self) -> Vec<JointFriction> {
        self.contact_frictions = (0..self.rigid_contacts.len())
            .filter(|&k| self.rigid_contacts[k].friction.is_some())
            .collect();
        let joints = self
            .frictions
            .iter()
            .map(|f| f.spec(self.constraints.row_offset(f.constraint)));
        let contacts = self.contact_frictions.iter().map(|&k| {
            let c = &self.rigid_contacts[k];
            JointFriction {
                element: "contact",
                name: c.name.clone(),
                coefficient: c.friction.unwrap_or(0.0),
                viscous: 0.0,
                constant: 0.0,
                load_rows: Vec::new(),
                load_limit: Some(self.limits.len() + k),
                stick_speed: crate::STICK_SPEED,
                cone: None,
            }
        });
        joints.chain(contacts).collect()
    }

    /// The rigid contacts with friction, in the order of their friction elements (after the
    /// joints'), as indices into [`Model::rigid_contacts`].
    pub fn contact_frictions(&self) -> &[usize] {
        &self.contact_frictions
    }

    /// The joints with friction.
    pub fn frictions(&self) -> &[Friction] {
        &self.frictions
    }

    /// The model with limits on some of its revolute and prismatic joints (`docs/limits.md`).
    /// Errors name the joint.
    pub fn with_limits(mut self, limits: Vec<Limit>) -> Result<Self, ConstraintError> {
        for l in &limits {
            l.validate()?;
            if l.constraint >= self.constraints.constraints().len()
                || self.constraints.constraints()[l.constraint].name() != l.name()
            {
                return Err(dalembert_system::ModelError::InvalidParameter {
                    element: format!("joint '{}'", l.name()),
                    what: "a limit refers to a joint the model does not hold".to_string(),
                }
                .into());
            }
        }
        self.limits = limits;
        self.limit_specs = self.unilateral_specs();
        self.friction_specs = self.friction_elements();
        Ok(self)
    }

    /// The model with rigid circle–line contacts (`docs/limits.md`, "Rigid contact"), each
    /// checked at the file's configuration `q0`. Errors name the contact.
    pub fn with_rigid_contacts(mut self, contacts: Vec<RigidContact>, q0: &[f64]) -> Result<Self, ConstraintError> {
        for c in &contacts {
            c.validate(q0)?;
        }
        self.rigid_contacts = contacts;
        self.limit_specs = self.unilateral_specs();
        self.friction_specs = self.friction_elements();
        Ok(self)
    }

    /// The rigid contacts.
    pub fn rigid_contacts(&self) -> &[RigidContact] {
        &self.rigid_contacts
    }

    fn unilateral_specs(&self) -> Vec<JointLimit> {
        let joints = self.limits.iter().map(Limit::spec);
        joints
            .chain(self.rigid_contacts.iter().map(RigidContact::spec))
            .collect()
    }

    /// The joints with limits.
    pub fn limits(&self) -> &[Limit] {
        &self.limits
    }

    /// The moving bodies, in coordinate order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The applied force elements.
    pub fn forces(&self) -> &[Box<dyn ForceElement>] {
        &self.forces
    }

    /// The planar constraint system (the seam sees it as [`MultibodySystem::constraints`]).
    pub fn constraints(&self) -> &ConstraintSystem {
        &self.constraints
    }

    /// Number of coordinates `n` (positions and velocities alike: `v = q̇`).
    pub fn num_coordinates(&self) -> usize {
        3 * self.bodies.len()
    }

    /// The mass matrix at `q`, as 3×3 blocks.
    pub fn mass_matrix(&self, q: &[f64]) -> MassMatrix {
        MassMatrix::new(&self.bodies, q)
    }
}

impl MultibodySystem for Model {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    fn constraints(&self) -> &dyn ConstraintSet {
        &self.constraints
    }

    /// `M_i` of `docs/equations.md` §1 per body (`dalembert_kinematics::mass`).
    fn mass(&self, q: &[f64], out: &mut BlockDiagonal) {
        for (i, b) in self.bodies.iter().enumerate() {
            let blk = MassMatrix::block(b, q[3 * i + 2]);
            let o = out.block_mut(i);
            for r in 0..3 {
                for c in 0..3 {
                    o[3 * r + c] = blk[(r, c)];
                }
            }
        }
    }

    fn mass_is_constant(&self) -> bool {
        self.mass_is_constant
    }

    fn frictions(&self) -> &[JointFriction] {
        &self.friction_specs
    }

    /// A joint's slip row, or (after the joints') a rigid contact's at its contact point.
    fn slip_row(&self, k: usize, _t: f64, q: &[f64], v: &[f64], row: &mut SlipRow) {
        match self.frictions.get(k) {
            Some(f) => f.slip_row(q, v, row),
            None => self.rigid_contacts[self.contact_frictions[k - self.frictions.len()]].slip_row(q, v, row),
        }
    }

    fn limits(&self) -> &[JointLimit] {
        &self.limit_specs
    }

    /// A joint limit's row, or (after the joint limits) a rigid contact's gap row.
    fn limit_row(&self, k: usize, _t: f64, q: &[f64], v: &[f64], row: &mut SlipRow) -> f64 {
        match self.limits.get(k) {
            Some(l) => l.limit_row(q, v, row),
            None => self.rigid_contacts[k - self.limits.len()].gap_row(q, v, row),
        }
    }

    /// The moving bodies of each force element ([`ForceElement::bodies`]); `None` when an element
    /// does not declare them.
    fn force_coupling(&self) -> Option<Vec<Vec<usize>>> {
        self.forces
            .iter()
            .map(|f| Some(f.bodies()?.iter().filter_map(|b| b.id().map(|id| id.0)).collect()))
            .collect()
    }

    /// `∂(C_qᵀ λ)/∂q` from each constraint's [`crate::Constraint::weighted_hessian`] and `−∂Q/∂q`,
    /// `−∂Q/∂q̇` from each force element's [`dalembert_kinematics::ForceElement::add_tangent`], and
    /// the terms of offset centres of mass (`∂(M(θ) q̈)/∂θ`, the quadratic-velocity force); `false`
    /// when some element has no analytic derivatives.
    fn residual_tangent(
        &self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        (qdd, lambda): (&[f64], &[f64]),
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        use dalembert_kinematics::second_derivatives::add_pair;
        let n = self.layout.n_v();
        if q.len() != n || v.len() != n || qdd.len() != n || lambda.len() != self.num_equations() {
            return false;
        }
        // Offset centres of mass (`dalembert_kinematics::mass`): with `a = A c`, the block's
        // `m perp(a)` has `∂/∂θ = −m a`, and `Q_v = m a θ̇²` has `∂/∂θ = m perp(a) θ̇²`,
        // `∂/∂θ̇ = 2 m a θ̇`.
        for (i, body) in self.bodies.iter().enumerate() {
            if body.center_of_mass == dalembert_kinematics::Vec2::zeros() {
                continue;
            }
            let (k, m) = (3 * i, body.mass);
            let a = dalembert_kinematics::rotation(q[k + 2]) * body.center_of_mass;
            let w = v[k + 2];
            let pa = dalembert_kinematics::perp(a);
            for r in 0..2 {
                out.add_q(k + r, k + 2, -m * a[r] * qdd[k + 2] - m * pa[r] * w * w);
                out.add_v(k + r, k + 2, -2.0 * m * a[r] * w);
            }
            out.add_q(k + 2, k + 2, -m * (a.x * qdd[k] + a.y * qdd[k + 1]));
        }
        for (k, c) in self.constraints.constraints().iter().enumerate() {
            let [a, b] = c.bodies();
            let (sa, sb) = (BodyState::of(a, q, v), BodyState::of(b, q, v));
            let r0 = self.constraints.row_offset(k);
            let Some(h) = c.weighted_hessian(t, &sa, &sb, &lambda[r0..r0 + c.num_equations()]) else {
                return false;
            };
            add_pair(out, [a, b], &h, 1.0, false);
        }
        for f in &self.forces {
            if !f.add_tangent(t, &self.bodies, q, v, out) {
                return false;
            }
        }
        !out.outside()
    }

    /// `Q_e`: all applied generalized forces plus the quadratic-velocity force of offset centres of
    /// mass, written (not added) into `q_e`. Allocates nothing.
    fn applied_forces(&self, t: f64, q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        q_e.iter_mut().for_each(|x| *x = 0.0);
        for f in &self.forces {
            f.add_generalized_force(t, &self.bodies, q, qd, q_e);
        }
        MassMatrix::add_quadratic_velocity_force(&self.bodies, q, qd, q_e);
    }

    /// `Ok` when `q_e` is finite; otherwise the error names the force element whose generalized
    /// force overflows or is not a number (found by evaluating each element alone: only on this
    /// failure path).
    fn check_forces(&self, t: f64, q: &[f64], qd: &[f64], q_e: &[f64]) -> Result<(), DynamicsError> {
        if dalembert_system::all_finite(q_e) {
            return Ok(());
        }
        let mut one = vec![0.0; q_e.len()];
        let what = self
            .forces
            .iter()
            .find(|f| {
                one.iter_mut().for_each(|x| *x = 0.0);
                f.add_generalized_force(t, &self.bodies, q, qd, &mut one);
                one.iter().any(|x| !x.is_finite())
            })
            .map_or_else(
                || "quadratic-velocity force of an offset centre of mass (velocities overflow)".to_string(),
                |f| {
                    format!(
                        "or overflowing generalized force of '{}' (check its parameters and the state)",
                        f.name()
                    )
                },
            );
        Err(DynamicsError::NonFinite { time: t, what })
    }

    /// Kinetic energy `½ q̇ᵀ M q̇`, computed body by body without building `M` (no trigonometry
    /// for bodies whose reference point is the centre of mass).
    fn kinetic_energy(&self, q: &[f64], qd: &[f64]) -> f64 {
        self.bodies
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let v = nalgebra::Vector3::new(qd[3 * i], qd[3 * i + 1], qd[3 * i + 2]);
                if b.center_of_mass == dalembert_kinematics::Vec2::zeros() {
                    0.5 * (b.mass * (v.x * v.x + v.y * v.y) + b.inertia * v.z * v.z)
                } else {
                    let blk = MassMatrix::block(b, q[3 * i + 2]);
                    0.5 * v.dot(&(blk * v))
                }
            })
            .sum()
    }

    /// The friction elements, the limits, then the contact elements (an element is one or not
    /// whatever the state: asked at zero).
    fn num_events(&self) -> usize {
        let q = vec![0.0; 3 * self.bodies.len()];
        self.friction_specs.len()
            + self.limit_specs.len()
            + self
                .forces
                .iter()
                .filter(|f| f.contact_gap(&self.bodies, &q).is_some())
                .count()
    }

    /// Each friction element's slip rate (0 within its stick speed), then each limit's distance
    /// to its nearer bound, then each contact element's gap, in the order of the force elements.
    fn events(&self, _t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        let mut row = SlipRow::default();
        let (slips, rest) = out.split_at_mut(self.friction_specs.len().min(out.len()));
        let (stops, gaps) = rest.split_at_mut(self.limit_specs.len().min(rest.len()));
        for (k, (slot, spec)) in stops.iter_mut().zip(&self.limit_specs).enumerate() {
            *slot = spec.free_event(self.limit_row(k, 0.0, q, &[], &mut row));
        }
        for (k, (slot, spec)) in slips.iter_mut().zip(&self.friction_specs).enumerate() {
            MultibodySystem::slip_row(self, k, 0.0, q, v, &mut row);
            let w = row.dot(v);
            *slot = if w.abs() > spec.stick_speed { w } else { 0.0 };
        }
        let contacts = self.forces.iter().filter_map(|f| f.contact_gap(&self.bodies, q));
        for (slot, gap) in gaps.iter_mut().zip(contacts) {
            *slot = gap;
        }
    }

    /// Total potential energy of the conservative elements at `(t, q)`.
    fn potential_energy(&self, t: f64, q: &[f64]) -> f64 {
        self.forces
            .iter()
            .filter_map(|f| f.potential_energy(t, &self.bodies, q))
            .sum()
    }

    /// `Σ vᵀ Q_f + dV/dt` over the force elements: the default of the seam without the
    /// quadratic-velocity force of offset centres of mass, an inertial term that does work in
    /// these coordinates.
    fn nonconservative_power(&self, t: f64, q: &[f64], qd: &[f64], scratch: &mut PowerScratch) -> f64 {
        if self.forces.iter().all(|f| f.is_conservative()) {
            return 0.0;
        }
        scratch.forces.iter_mut().for_each(|x| *x = 0.0);
        for f in &self.forces {
            f.add_generalized_force(t, &self.bodies, q, qd, &mut scratch.forces);
        }
        let applied: f64 = qd.iter().zip(&scratch.forces).map(|(a, b)| a * b).sum();
        applied + dalembert_system::system::potential_rate(self, t, q, qd, scratch)
    }

    /// Every force element is conservative, no joint has friction or limits (an impact takes
    /// energy) and no constraint is driven (a driver does work).
    fn is_conservative(&self) -> bool {
        self.frictions.is_empty()
            && self.limit_specs.is_empty()
            && self.forces.iter().all(|f| f.is_conservative())
            && self
                .constraints
                .constraints()
                .iter()
                .all(|c| c.role() != crate::ConstraintRole::Driver)
    }

    fn is_driven(&self) -> bool {
        self.constraints
            .constraints()
            .iter()
            .any(|c| c.role() == crate::ConstraintRole::Driver)
    }

    fn bodies_without_inertia(&self) -> Vec<String> {
        self.bodies
            .iter()
            .filter(|b| b.mass == 0.0 || b.inertia_about_reference() == 0.0)
            .map(|b| b.name.clone())
            .collect()
    }
}
