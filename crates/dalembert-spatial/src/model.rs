//! The spatial model: bodies, joints and forces, and its implementation of the system seam.
//!
//! Per body, positions `q = (r, p)` (centre of mass, Euler parameters: 7) and velocities
//! `v = (ṙ, ω')` (centre-of-mass velocity in global components, angular velocity in the body
//! frame: 6), so that the mass matrix is constant and block diagonal (Newton–Euler form,
//! Nikravesh §6.4; Haug §11.2):
//!
//! ```text
//! [m I   0 ] [r̈ ]   [ m g + Σ F                  ]
//! [ 0   J' ] [ω̇'] = [ −ω' × J'ω' + Σ Aᵀ(s × F) + Aᵀ T ] − C_qᵀ λ
//! ṗ = ½ p ⊗ (0, ω')
//! ```
//!
//! `C_q` is the Jacobian with respect to `v` (columns `ṙ`, `ω'`); a correction `Δ = (Δr, Δθ')`
//! moves the positions by `r + Δr`, `p ⊗ exp(Δθ'/2)`.

use crate::couplings::{Coupling, CouplingData};
use crate::euler_parameters::{self, rotate_body};
use crate::forces::ForceData;
use crate::frame::{self, Frame, NQ, NV, POSITION_LABELS, VELOCITY_LABELS};
use crate::joints::primitives::Row;
use crate::joints::JointData;
use crate::{Body, BodyRef, Driver, Force, Joint};
use dalembert_system::{
    BlockDiagonal, ConstraintPattern, ConstraintSet, ConstraintValues, DynamicsError, EquationRef, Layout, ModelError,
    MultibodySystem,
};
use nalgebra::{Matrix3, Vector3};

/// Collects bodies, joints and forces; [`ModelBuilder::build`] checks them and makes the model.
#[derive(Debug, Clone, Default)]
pub struct ModelBuilder {
    gravity: [f64; 3],
    bodies: Vec<Body>,
    joints: Vec<Joint>,
    drivers: Vec<Driver>,
    forces: Vec<Force>,
    couplings: Vec<Coupling>,
}

impl ModelBuilder {
    /// An empty model with gravitational acceleration `gravity` (global).
    pub fn new(gravity: [f64; 3]) -> Self {
        ModelBuilder {
            gravity,
            ..Default::default()
        }
    }

    /// Adds a body; returns the reference joints and forces use.
    pub fn body(&mut self, body: Body) -> BodyRef {
        self.bodies.push(body);
        BodyRef::Body(self.bodies.len() - 1)
    }

    /// Adds a joint (placed in the initial configuration).
    pub fn joint(&mut self, joint: Joint) -> &mut Self {
        self.joints.push(joint);
        self
    }

    /// Adds a driver (a prescribed motion).
    pub fn driver(&mut self, driver: Driver) -> &mut Self {
        self.drivers.push(driver);
        self
    }

    /// Adds a force element.
    pub fn force(&mut self, force: Force) -> &mut Self {
        self.forces.push(force);
        self
    }

    /// Adds a coupling between two joints' values (`docs/couplings.md`).
    pub fn coupling(&mut self, coupling: Coupling) -> &mut Self {
        self.couplings.push(coupling);
        self
    }

    /// Checks every element (errors name the element and what is wrong) and builds the model.
    pub fn build(self) -> Result<Model, ModelError> {
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return Err(ModelError::InvalidParameter {
                element: "gravity".into(),
                what: "must be finite".into(),
            });
        }
        for b in &self.bodies {
            b.validate()?;
        }
        let count = self.bodies.len();
        let initial: Vec<Frame> = self
            .bodies
            .iter()
            .map(|b| Frame {
                r: b.position,
                a: euler_parameters::rotation(&b.orientation),
                v: b.velocity,
                w: b.angular_velocity,
            })
            .collect();
        let frame_of = |b: Option<usize>| b.map_or(Frame::GROUND, |i| initial[i]);
        let index = |element: &str, b: BodyRef| match b {
            BodyRef::Ground => Ok(None),
            BodyRef::Body(i) if i < count => Ok(Some(i)),
            BodyRef::Body(index) => Err(ModelError::UnknownBody {
                element: element.to_string(),
                index,
                count,
            }),
        };
        let mut joints = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let element = format!("joint '{}'", j.name);
            let (bi, bj) = (index(&element, j.body_i)?, index(&element, j.body_j)?);
            joints.push(JointData::new(j, bi, bj, &frame_of(bi), &frame_of(bj))?);
        }
        let couplings = self
            .couplings
            .iter()
            .map(|c| CouplingData::new(c, &joints))
            .collect::<Result<Vec<_>, _>>()?;
        let mut drivers = Vec::with_capacity(self.drivers.len());
        for d in &self.drivers {
            let element = format!("driver '{}'", d.name);
            drivers.push(d.data(&joints, &|b| index(&element, b))?);
        }
        let mut forces = Vec::with_capacity(self.forces.len());
        for f in &self.forces {
            let element = format!("force '{}'", f.name());
            if let Force::User(u) = f {
                for b in u.bodies() {
                    index(&element, b)?;
                }
            }
            forces.push(ForceData::new(f, &|b| index(&element, b), &frame_of, &joints)?);
        }
        let layout = Layout::new(
            self.bodies
                .iter()
                .map(|b| (b.name.as_str(), POSITION_LABELS, VELOCITY_LABELS)),
        );
        // Rows: the joints', the couplings', the drivers'.
        let mut segments = Vec::new();
        let mut equations = Vec::new();
        fn rows_of(ji: usize, j: &JointData, equations: &mut Vec<(usize, usize)>, segments: &mut Vec<(usize, usize)>) {
            for k in 0..j.num_equations() {
                let row = equations.len();
                equations.push((ji, k));
                segments.extend(j.body_i.map(|b| (row, b)));
                segments.extend(j.body_j.map(|b| (row, b)));
            }
        }
        for (ji, j) in joints.iter().enumerate() {
            rows_of(ji, j, &mut equations, &mut segments);
        }
        for (k, c) in couplings.iter().enumerate() {
            let row = equations.len();
            equations.push((joints.len() + k, 0));
            segments.extend(c.bodies.iter().map(|&b| (row, b)));
        }
        for (d, j) in drivers.iter().enumerate() {
            rows_of(joints.len() + couplings.len() + d, j, &mut equations, &mut segments);
        }
        let pattern = ConstraintPattern::from_segments(equations.len(), &layout, segments);
        Ok(Model {
            gravity: Vector3::from(self.gravity),
            bodies: self.bodies,
            joints,
            couplings,
            drivers,
            forces,
            force_names: self.forces.iter().map(|f| f.name().to_string()).collect(),
            layout,
            pattern,
            equations,
            limits: Vec::new(),
            limited_joints: Vec::new(),
            contacts: Vec::new(),
            frictions: Vec::new(),
            friction_joints: Vec::new(),
            friction_contacts: Vec::new(),
        })
    }
}

/// A spatial multibody model (build it with [`ModelBuilder`]).
#[derive(Debug, Clone)]
pub struct Model {
    gravity: Vector3<f64>,
    bodies: Vec<Body>,
    joints: Vec<JointData>,
    /// Couplings between joint values (their rows follow the joints').
    couplings: Vec<CouplingData>,
    /// Drivers, as constraints after the joints (their rows follow the couplings' rows).
    drivers: Vec<JointData>,
    forces: Vec<ForceData>,
    /// The force elements' names (messages).
    force_names: Vec<String>,
    layout: Layout,
    pattern: ConstraintPattern,
    /// `(joint, coupling or driver, equation within it)` of every row (couplings numbered after
    /// the joints, drivers after the couplings).
    equations: Vec<(usize, usize)>,
    /// Joint limits (`docs/limits.md`), and the index of each one's joint.
    pub(crate) limits: Vec<dalembert_system::JointLimit>,
    pub(crate) limited_joints: Vec<usize>,
    /// Rigid contacts (their limits follow the joints' in `limits`).
    pub(crate) contacts: Vec<crate::limits::ContactData>,
    /// Joint friction (`docs/friction.md`), and the index of each element's joint.
    pub(crate) frictions: Vec<dalembert_system::JointFriction>,
    pub(crate) friction_joints: Vec<usize>,
    /// The rigid contacts with friction (indices into `contacts`), in the order of their friction
    /// cones: two elements each, after the joints' ([`crate::contact_friction`]).
    pub(crate) friction_contacts: Vec<usize>,
}

/// Most rows a joint primitive has.
const MAX_PRIMITIVE_ROWS: usize = 3;

/// Values of one cached [`Frame`]: `r`, `A` (column-major), `v`, `ω`.
const FRAME_LEN: usize = 18;

fn store_frame(f: &Frame, s: &mut [f64]) {
    s[..3].copy_from_slice(f.r.as_slice());
    s[3..12].copy_from_slice(f.a.as_slice());
    s[12..15].copy_from_slice(f.v.as_slice());
    s[15..18].copy_from_slice(f.w.as_slice());
}

fn load_frame(s: &[f64]) -> Frame {
    Frame {
        r: Vector3::from_column_slice(&s[..3]),
        a: Matrix3::from_column_slice(&s[3..12]),
        v: Vector3::from_column_slice(&s[12..15]),
        w: Vector3::from_column_slice(&s[15..18]),
    }
}

impl Model {
    /// The bodies, in layout order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The joints in body-frame terms, in order (their equations are the rows of `C`).
    pub(crate) fn joints(&self) -> &[JointData] {
        &self.joints
    }

    /// Names of the joints, in order (the order of [`Model::reactions`]).
    pub fn joint_names(&self) -> impl Iterator<Item = &str> {
        self.joints.iter().map(|j| j.name.as_str())
    }

    /// Names of the drivers, in order (the order of [`Model::driver_efforts`]).
    pub fn driver_names(&self) -> impl Iterator<Item = &str> {
        self.drivers.iter().map(|d| d.name.as_str())
    }

    /// Each driver's effort `−λ` (torque about a driven joint axis, force along a driven
    /// displacement or coordinate, on the driven body), from the multipliers of all equations.
    pub fn driver_efforts(&self, lambda: &[f64]) -> Vec<f64> {
        let first = lambda.len() - self.drivers.len();
        lambda[first..].iter().map(|l| -l).collect()
    }

    /// Joints then drivers (the couplings' rows lie between them).
    fn constraint_data(&self) -> impl Iterator<Item = &JointData> {
        self.joints.iter().chain(&self.drivers)
    }

    /// Names of the couplings, in order (the order of [`Model::coupling_efforts`]).
    pub fn coupling_names(&self) -> impl Iterator<Item = &str> {
        self.couplings.iter().map(|c| c.name.as_str())
    }

    /// The index of the first coupling's row (the joints' rows come before it).
    fn first_coupling_row(&self) -> usize {
        self.joints.iter().map(JointData::num_equations).sum()
    }

    /// Each coupling's effort `−λ`: the torque about (or force along) its follower joint's axis
    /// on the follower's second body, from the multipliers of all equations.
    /// Allocates nothing.
    pub fn coupling_efforts<'a>(&self, lambda: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        let first = self.first_coupling_row();
        lambda[first..first + self.couplings.len()].iter().map(|l| -l)
    }

    /// The force elements, in order.
    pub(crate) fn force_data(&self) -> &[ForceData] {
        &self.forces
    }

    /// Names of the force elements, in order.
    pub fn force_names(&self) -> impl Iterator<Item = &str> {
        self.force_names.iter().map(|n| n.as_str())
    }

    /// Names of the compliant contact elements (`docs/contact.md`), in the order of the force
    /// elements: those [`Model::contact_resultants_into`] fills.
    pub fn contact_names(&self) -> impl Iterator<Item = &str> {
        self.forces
            .iter()
            .zip(&self.force_names)
            .filter(|(f, _)| f.is_contact())
            .map(|(_, n)| n.as_str())
    }

    /// Each compliant contact's resultant at the state `(q, v)` into `out` (one per
    /// [`Model::contact_names`]): its gap, normal force, force on its body and centre of pressure
    /// ([`dalembert_system::ContactResultant`]). Allocates nothing.
    pub fn contact_resultants_into(&self, q: &[f64], v: &[f64], out: &mut [dalembert_system::ContactResultant<3>]) {
        let frame = |b: Option<usize>| self.frame(b, q, v);
        let resultants = self.forces.iter().filter_map(|f| f.resultant(&frame));
        for (slot, r) in out.iter_mut().zip(resultants) {
            *slot = r;
        }
    }

    /// Names of the force elements that do work beyond their potential (dampers, actuators,
    /// applied forces and torques), in order.
    pub fn nonconservative_force_names(&self) -> impl Iterator<Item = &str> {
        self.forces
            .iter()
            .zip(&self.force_names)
            .filter(|(f, _)| !f.is_conservative())
            .map(|(_, n)| n.as_str())
    }

    /// Gravitational acceleration.
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// `(q₀, v₀)` from the bodies' initial poses and velocities (orientations normalized,
    /// angular velocities converted to body frames). Not necessarily consistent with the joints:
    /// run the position and velocity analyses for that.
    pub fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        let mut q = Vec::with_capacity(NQ * self.bodies.len());
        let mut v = Vec::with_capacity(NV * self.bodies.len());
        for b in &self.bodies {
            let p = euler_parameters::normalized(&b.orientation);
            q.extend(b.position.iter().chain(&p));
            let w_body = euler_parameters::rotation(&p).transpose() * b.angular_velocity;
            v.extend(b.velocity.iter().chain(w_body.iter()));
        }
        (q, v)
    }

    /// The frame of body `b` (ground for `None`) at `(q, v)`.
    #[inline]
    pub fn frame(&self, b: Option<usize>, q: &[f64], v: &[f64]) -> Frame {
        b.map_or(Frame::GROUND, |i| Frame::of(i, q, v))
    }

    /// Angular velocity of body `b` in global components at `(q, v)`.
    pub fn angular_velocity(&self, b: usize, q: &[f64], v: &[f64]) -> Vector3<f64> {
        Frame::of(b, q, v).w
    }

    /// Angular momentum of the whole system about the origin (global).
    pub fn angular_momentum(&self, q: &[f64], v: &[f64]) -> Vector3<f64> {
        self.bodies.iter().enumerate().fold(Vector3::zeros(), |acc, (i, b)| {
            let f = Frame::of(i, q, v);
            let (_, w_body) = frame::velocity(i, v);
            acc + f.r.cross(&(b.mass * f.v)) + f.a * (b.inertia * w_body)
        })
    }
}

impl ConstraintSet for Model {
    fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }

    fn equation(&self, row: usize) -> EquationRef {
        let (ji, k) = self.equations[row];
        let (name, label) = match ji.checked_sub(self.joints.len()) {
            None => (&self.joints[ji].name, self.joints[ji].labels[k]),
            Some(c) if c < self.couplings.len() => (&self.couplings[c].name, "coupling"),
            Some(c) => {
                let d = &self.drivers[c - self.couplings.len()];
                (&d.name, d.labels[k])
            }
        };
        EquationRef {
            constraint: ji,
            name: name.clone(),
            equation: k,
            label,
        }
    }

    /// Storage sized for this system; the scratch holds each body's [`Frame`] (`FRAME_LEN` values).
    fn values(&self) -> ConstraintValues {
        ConstraintValues::new(&self.pattern, FRAME_LEN * self.bodies.len())
    }

    /// Evaluates every constraint, each body's frame computed once (into `out.scratch` when it has
    /// room, as [`Self::values`] gives it) rather than once per joint side. Allocates nothing.
    fn evaluate(&self, t: f64, q: &[f64], v: &[f64], out: &mut ConstraintValues) {
        let mut row = 0;
        let mut entry = 0;
        let mut rows = [Row::default(); MAX_PRIMITIVE_ROWS];
        let cached = out.scratch.len() >= FRAME_LEN * self.bodies.len();
        if cached {
            for (b, s) in out
                .scratch
                .chunks_exact_mut(FRAME_LEN)
                .take(self.bodies.len())
                .enumerate()
            {
                store_frame(&Frame::of(b, q, v), s);
            }
        }
        let scratch = std::mem::take(&mut out.scratch);
        let frame = |b: Option<usize>| match b {
            Some(b) if cached => load_frame(&scratch[FRAME_LEN * b..FRAME_LEN * (b + 1)]),
            _ => self.frame(b, q, v),
        };
        let mut joint_rows = |j: &JointData, row: &mut usize, entry: &mut usize, out: &mut ConstraintValues| {
            let (fi, fj) = (frame(j.body_i), frame(j.body_j));
            for prim in &j.primitives {
                let n = prim.len();
                prim.evaluate(t, &fi, &fj, &mut rows[..n]);
                for r in &rows[..n] {
                    out.c[*row] = r.c;
                    out.c_t[*row] = r.c_t;
                    out.gamma[*row] = r.gamma;
                    for (body, frame, [lin, ang]) in [(j.body_i, &fi, r.i), (j.body_j, &fj, r.j)] {
                        if body.is_some() {
                            // ∂/∂ω' = (∂/∂ω) A.
                            let ang_body = frame.a.transpose() * ang;
                            out.jacobian[*entry..*entry + 3].copy_from_slice(lin.as_slice());
                            out.jacobian[*entry + 3..*entry + 6].copy_from_slice(ang_body.as_slice());
                            *entry += NV;
                        }
                    }
                    *row += 1;
                }
            }
        };
        for j in &self.joints {
            joint_rows(j, &mut row, &mut entry, out);
        }
        for c in &self.couplings {
            let (value, gamma, ends) = c.row(&self.joints, &frame);
            out.c[row] = value;
            out.c_t[row] = 0.0;
            out.gamma[row] = gamma;
            // The ends on each of the row's bodies summed (two joints may share a body).
            for &b in &c.bodies {
                let (mut lin, mut ang) = (Vector3::zeros(), Vector3::zeros());
                for (_, [l, a]) in ends.iter().filter(|(e, _)| *e == Some(b)) {
                    lin += l;
                    ang += a;
                }
                let ang_body = frame(Some(b)).a.transpose() * ang;
                out.jacobian[entry..entry + 3].copy_from_slice(lin.as_slice());
                out.jacobian[entry + 3..entry + 6].copy_from_slice(ang_body.as_slice());
                entry += NV;
            }
            row += 1;
        }
        for j in &self.drivers {
            joint_rows(j, &mut row, &mut entry, out);
        }
        out.scratch = scratch;
    }

    fn correct_positions(&self, q: &mut [f64], delta: &[f64]) {
        self.integrate_positions(q, delta, 1.0);
        self.normalize(q);
    }

    fn describe_position(&self, i: usize) -> String {
        self.layout.describe_position(i)
    }
}

impl MultibodySystem for Model {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    fn constraints(&self) -> &dyn ConstraintSet {
        self
    }

    fn force_coupling(&self) -> Option<Vec<Vec<usize>>> {
        Some(self.forces.iter().map(ForceData::bodies).collect())
    }

    fn mass(&self, _q: &[f64], out: &mut BlockDiagonal) {
        for (i, b) in self.bodies.iter().enumerate() {
            let blk = out.block_mut(i);
            blk.fill(0.0);
            for k in 0..3 {
                blk[k * NV + k] = b.mass;
                for l in 0..3 {
                    blk[(3 + k) * NV + 3 + l] = b.inertia[(k, l)];
                }
            }
        }
    }

    fn mass_is_constant(&self) -> bool {
        true
    }

    fn reference_positions(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.layout.n_q()];
        for c in q.chunks_exact_mut(NQ) {
            c[3] = 1.0;
        }
        q
    }

    /// Analytic unless a force element is user-written (which makes the integrator difference the
    /// residual): `−∂Q/∂ω'` of the gyroscopic
    /// `−ω' × J ω'` is `[ω']× J − [J ω']×`, and each constraint primitive's wrench derivatives
    /// and each force element's (`joints::second_derivatives::WrenchDerivative`) are
    /// mapped to the velocity coordinates by `joints::second_derivatives::add_wrench`.
    fn residual_tangent(
        &self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        (_qdd, lambda): (&[f64], &[f64]),
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        use crate::joints::second_derivatives::{add_wrench, WrenchDerivative};
        let n = self.layout.n_v();
        if v.len() != n || q.len() != self.layout.n_q() || lambda.len() != self.pattern.rows() {
            return false;
        }
        for (i, b) in self.bodies.iter().enumerate() {
            let (_, w) = frame::velocity(i, v);
            let g = w.cross_matrix() * b.inertia - (b.inertia * w).cross_matrix();
            for r in 0..3 {
                for c in 0..3 {
                    out.add_v(NV * i + 3 + r, NV * i + 3 + c, g[(r, c)]);
                }
            }
        }
        if !self.couplings.is_empty() {
            // A coupling's second derivatives are not written out: the residual is differenced.
            return false;
        }
        let mut row = 0;
        for j in self.constraint_data() {
            let ends = [
                (j.body_i, self.frame(j.body_i, q, v)),
                (j.body_j, self.frame(j.body_j, q, v)),
            ];
            for prim in &j.primitives {
                let len = prim.len();
                let wd = WrenchDerivative::of(prim, t, &ends[0].1, &ends[1].1, &lambda[row..row + len]);
                row += len;
                add_wrench(out, [(ends[0].0, &ends[0].1), (ends[1].0, &ends[1].1)], &wd, 1.0);
            }
        }
        let frame = |b: Option<usize>| self.frame(b, q, v);
        for f in &self.forces {
            match f.wrench_derivative(t, &frame) {
                Some((bodies, wd)) => {
                    let frames = [frame(bodies[0]), frame(bodies[1])];
                    add_wrench(out, [(bodies[0], &frames[0]), (bodies[1], &frames[1])], &wd, -1.0);
                }
                None => return false,
            }
        }
        !out.outside()
    }

    fn applied_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        for (i, b) in self.bodies.iter().enumerate() {
            let (_, w) = frame::velocity(i, v);
            let gyro = -w.cross(&(b.inertia * w));
            let o = NV * i;
            for k in 0..3 {
                out[o + k] = b.mass * self.gravity[k];
                out[o + 3 + k] = gyro[k];
            }
        }
        let frame = |b: Option<usize>| self.frame(b, q, v);
        for f in &self.forces {
            f.add(t, &frame, out);
        }
    }

    fn check_forces(&self, t: f64, q: &[f64], v: &[f64], q_e: &[f64]) -> Result<(), DynamicsError> {
        let frame = |b: Option<usize>| self.frame(b, q, v);
        for (f, name) in self.forces.iter().zip(&self.force_names) {
            f.check(t, &frame).map_err(|what| DynamicsError::ForceElement {
                time: t,
                element: format!("force '{name}'"),
                what,
            })?;
        }
        if dalembert_system::all_finite(q_e) {
            return Ok(());
        }
        match q_e.iter().position(|x| !x.is_finite()) {
            None => Ok(()),
            Some(i) => Err(DynamicsError::NonFinite {
                time: t,
                what: format!("applied force {}", self.layout.describe_velocity(i)),
            }),
        }
    }

    fn position_rates(&self, q: &[f64], v: &[f64], out: &mut [f64]) {
        for i in 0..self.bodies.len() {
            let (_, p) = frame::position(i, q);
            let (lin, w) = frame::velocity(i, v);
            let o = NQ * i;
            out[o..o + 3].copy_from_slice(lin.as_slice());
            out[o + 3..o + 7].copy_from_slice(&euler_parameters::rates(&p, &w));
        }
    }

    fn integrate_positions(&self, q: &mut [f64], v: &[f64], h: f64) {
        for i in 0..self.bodies.len() {
            let (lin, w) = frame::velocity(i, v);
            let o = NQ * i;
            for k in 0..3 {
                q[o + k] += h * lin[k];
            }
            let (_, mut p) = frame::position(i, q);
            rotate_body(&mut p, &(h * w));
            q[o + 3..o + 7].copy_from_slice(&p);
        }
    }

    fn chart_rates(&self, delta: &[f64], v: &[f64], out: &mut [f64]) {
        for i in 0..self.bodies.len() {
            let (lin, w) = frame::velocity(i, v);
            let (_, phi) = frame::velocity(i, delta);
            let o = NV * i;
            out[o..o + 3].copy_from_slice(lin.as_slice());
            out[o + 3..o + 6].copy_from_slice(euler_parameters::inverse_right_jacobian(&phi, &w).as_slice());
        }
    }

    fn normalize(&self, q: &mut [f64]) {
        for c in q.chunks_exact_mut(NQ) {
            let p = euler_parameters::normalized(&[c[3], c[4], c[5], c[6]]);
            c[3..].copy_from_slice(&p);
        }
    }

    fn kinetic_energy(&self, _q: &[f64], v: &[f64]) -> f64 {
        self.bodies
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (lin, w) = frame::velocity(i, v);
                0.5 * (b.mass * lin.norm_squared() + w.dot(&(b.inertia * w)))
            })
            .sum()
    }

    /// The friction elements, the limits, then the contact elements.
    fn num_events(&self) -> usize {
        self.frictions.len() + self.limits.len() + self.forces.iter().filter(|f| f.is_contact()).count()
    }

    /// Each limit's distance to its nearer bound, then each contact element's gap, in the order
    /// of the force elements.
    fn events(&self, _t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        let mut row = dalembert_system::SlipRow::default();
        let (slips, rest) = out.split_at_mut(self.frictions.len().min(out.len()));
        for (k, slot) in slips.iter_mut().enumerate() {
            self.slip_row_into(k, q, v, &mut row);
            let w = row.dot(v);
            *slot = if w.abs() > self.frictions[k].stick_speed {
                w
            } else {
                0.0
            };
        }
        let (stops, gaps) = rest.split_at_mut(self.limits.len().min(rest.len()));
        for (k, slot) in stops.iter_mut().enumerate() {
            *slot = self.limits[k].free_event(self.limit_row_into(k, q, &[], &mut row));
        }
        let frame = |b: Option<usize>| self.frame(b, q, &[]);
        for (slot, gap) in gaps.iter_mut().zip(self.forces.iter().filter_map(|f| f.gap(&frame))) {
            *slot = gap;
        }
    }

    fn limits(&self) -> &[dalembert_system::JointLimit] {
        &self.limits
    }

    fn frictions(&self) -> &[dalembert_system::JointFriction] {
        &self.frictions
    }

    fn slip_row(&self, k: usize, _t: f64, q: &[f64], v: &[f64], row: &mut dalembert_system::SlipRow) {
        self.slip_row_into(k, q, v, row);
    }

    fn limit_row(&self, k: usize, _t: f64, q: &[f64], v: &[f64], row: &mut dalembert_system::SlipRow) -> f64 {
        self.limit_row_into(k, q, v, row)
    }

    fn potential_energy(&self, t: f64, q: &[f64]) -> f64 {
        let gravity: f64 = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| -b.mass * self.gravity.dot(&frame::position(i, q).0))
            .sum();
        let frame = |b: Option<usize>| self.frame(b, q, &[]);
        gravity + self.forces.iter().map(|f| f.potential(t, &frame)).sum::<f64>()
    }

    /// Every force element is conservative, nothing is driven (a driver does work) and no joint
    /// has limits (an impact takes energy).
    fn is_conservative(&self) -> bool {
        self.forces.iter().all(ForceData::is_conservative)
            && self.drivers.is_empty()
            && self.limits.is_empty()
            && self.frictions.is_empty()
    }

    fn is_driven(&self) -> bool {
        !self.drivers.is_empty()
    }

    fn bodies_without_inertia(&self) -> Vec<String> {
        self.bodies
            .iter()
            .filter(|b| b.lacks_inertia())
            .map(|b| b.name.clone())
            .collect()
    }
}
