//! Limits on spatial revolute and prismatic joints (`docs/limits.md`): each limited joint's
//! coordinate (its joint value, [`crate::joint_values`]), the row of its rate and the bias of its
//! acceleration, for the seam's impact and resting law ([`dalembert_system::limit`]).
//!
//! With the joint frame's axes `x_i, y_i, z_i` on body `i`, `x_j` on body `j`, its points'
//! global arms `s_i`, `s_j` from the centres of mass, and `d = r_j + s_j − r_i − s_i`:
//!
//! ```text
//! revolute:  θ = atan2(x_j·y_i, x_j·x_i),  w = z_i·(ω_j − ω_i)
//!            g: ω'_j ↦ A_jᵀ z_i,  ω'_i ↦ −A_iᵀ z_i;            b = ż_i·(ω_j − ω_i)
//! prismatic: s = z_i·d,  w = ż_i·d + z_i·ḋ
//!            g: ṙ_j ↦ z_i,  ṙ_i ↦ −z_i,  ω'_j ↦ A_jᵀ (s_j × z_i),  ω'_i ↦ A_iᵀ (z_i × (d + s_i))
//!            b = (ω_i × ż_i)·d + 2 ż_i·ḋ + z_i·(ω_j × (ω_j × s_j) − ω_i × (ω_i × s_i))
//! ```
//!
//! with `ż_i = ω_i × z_i` (`b` is `ẅ` at zero accelerations). The angle is measured within a
//! turn; its limit says so ([`JointLimit::within_turn`]), and the switching formulation follows
//! it across half turns, so a revolute joint's bounds may lie beyond `±π`.

use crate::frame::NV;
use crate::joints::JointKind;
use crate::Model;
use dalembert_system::{ContactResultant, JointLimit, ModelError, SlipRow};
use nalgebra::Vector3;

impl Model {
    /// The model with limits on some of its revolute and prismatic joints (each limit names its
    /// joint). Errors name the joint.
    pub fn with_limits(mut self, mut limits: Vec<JointLimit>) -> Result<Self, ModelError> {
        let mut joints = Vec::with_capacity(limits.len());
        for l in &mut limits {
            let bad = |what: String| ModelError::InvalidParameter {
                element: format!("joint '{}'", l.name),
                what,
            };
            l.check().map_err(bad)?;
            let index = self
                .joints()
                .iter()
                .position(|j| j.name == l.name)
                .ok_or_else(|| bad("a limit refers to a joint the model does not hold".into()))?;
            match self.joints()[index].kind {
                // Its angle is measured within a turn: the switching formulation follows it.
                Some(JointKind::Revolute) => l.within_turn = true,
                Some(JointKind::Prismatic) => {}
                _ => return Err(bad("limits are for revolute and prismatic joints".into())),
            }
            if l.lower > 0.0 || l.upper < 0.0 {
                return Err(bad(format!(
                    "the joint starts outside its limits [{}, {}] (its value is 0 in the file's configuration)",
                    l.lower, l.upper
                )));
            }
            joints.push(index);
        }
        self.limits = limits;
        self.limited_joints = joints;
        self.contacts.clear();
        self.friction_contacts.clear();
        self.add_contact_frictions();
        Ok(self)
    }

    /// The joint limits, in order.
    pub fn limit_specs(&self) -> &[JointLimit] {
        &self.limits
    }

    /// The row of limit `k` at `(q, v)` into `row`, and the joint's value (or, after the joint
    /// limits, a rigid contact's gap).
    pub(crate) fn limit_row_into(&self, k: usize, q: &[f64], v: &[f64], row: &mut SlipRow) -> f64 {
        match self.limited_joints.get(k) {
            Some(&joint) => self.joint_row_into(joint, q, v, row),
            None => self.contact_row_into(k - self.limited_joints.len(), q, v, row),
        }
    }

    /// The row of revolute or prismatic joint `joint`'s value at `(q, v)` into `row` (the
    /// formulas above), and the value.
    pub(crate) fn joint_row_into(&self, joint: usize, q: &[f64], v: &[f64], row: &mut SlipRow) -> f64 {
        let j = &self.joints()[joint];
        let (fi, fj) = (self.frame(j.body_i, q, v), self.frame(j.body_j, q, v));
        let (r, _) = crate::couplings::joint_value_row(j, &fi, &fj);
        row.clear();
        for (part, offset) in [(0, 0), (1, 3)] {
            for (body, f, g) in [(j.body_j, &fj, r.j[part]), (j.body_i, &fi, r.i[part])] {
                let Some(b) = body else { continue };
                // ∂/∂ω' = (∂/∂ω) A.
                let g = if part == 1 { f.a.transpose() * g } else { g };
                for (c, x) in g.iter().enumerate() {
                    if *x != 0.0 {
                        row.push(NV * b + offset + c, *x);
                    }
                }
            }
        }
        row.bias = -r.gamma;
        r.c
    }
}

/// A sphere on a body in rigid (unilateral) contact with a plane of the ground, without friction
/// (`docs/limits.md`, "Rigid contact"): a limit on the gap `s = n·(c − p₀) − R ≥ 0`, with
///
/// ```text
/// w = n·(ṙ + ω × s_c),   g: ṙ ↦ n,  ω' ↦ Aᵀ (s_c × n),   b = n·(ω × (ω × s_c))
/// ```
///
/// where `c = r + s_c` is the sphere's centre and `s_c` its global arm from the centre of mass.
/// A plane fixed in a body moves with it: the gap is then a prismatic joint's value with the
/// plane's body as `i` and its normal as `z_i` (the formulas at the top of this module).
#[derive(Debug, Clone, PartialEq)]
pub struct SpherePlaneContact {
    /// The contact's name.
    pub name: String,
    /// The body carrying the sphere (its index).
    pub body: usize,
    /// The sphere's centre, global, in the file's configuration.
    pub centre: [f64; 3],
    /// The sphere's radius (m).
    pub radius: f64,
    /// A point of the plane (global, in the file's configuration).
    pub point: [f64; 3],
    /// The plane's normal, towards the sphere (global, in the file's configuration; any length
    /// but zero).
    pub normal: [f64; 3],
    /// The body carrying the plane (`None`: the ground).
    pub plane_body: Option<usize>,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which the sphere rests on the plane (m/s).
    pub rest_speed: f64,
    /// Coulomb's coefficient `μ ≥ 0` of the friction in the plane of contact
    /// ([`crate::contact_friction`]); `None`: frictionless.
    pub friction: Option<f64>,
}

/// Two spheres on two bodies (one may be the ground) in rigid (unilateral) contact, with or
/// without friction (`docs/limits.md`, "Rigid contact"): a limit on the gap
/// `s = |c_j − c_i| − R_i − R_j ≥ 0`, with `n = (c_j − c_i)/|c_j − c_i|`,
///
/// ```text
/// w = n·(ċ_j − ċ_i),   g: ṙ_j ↦ n,  ω'_j ↦ A_jᵀ (s_j × n),  ṙ_i ↦ −n,  ω'_i ↦ −A_iᵀ (s_i × n)
/// b = n·(ω_j × (ω_j × s_j) − ω_i × (ω_i × s_i)) + (|ḋ|² − (n·ḋ)²) / |d|
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SphereSphereContact {
    /// The contact's name.
    pub name: String,
    /// The two bodies (`None`: the ground).
    pub bodies: [Option<usize>; 2],
    /// The spheres' centres, global, in the file's configuration.
    pub centres: [[f64; 3]; 2],
    /// Their radii (m).
    pub radii: [f64; 2],
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which the spheres rest on each other (m/s).
    pub rest_speed: f64,
    /// Coulomb's coefficient `μ ≥ 0` of the friction in the plane of contact
    /// ([`crate::contact_friction`]); `None`: frictionless.
    pub friction: Option<f64>,
}

/// What [`Model::sphere_pair`] finds.
pub(crate) struct SpherePair {
    /// The first and second sphere's bodies' frames.
    pub fi: crate::frame::Frame,
    pub fj: crate::frame::Frame,
    /// The centres' global arms from their bodies' centres of mass.
    pub si: Vector3<f64>,
    pub sj: Vector3<f64>,
    /// `d = c_j − c_i`, `ḋ`, `|d|`.
    pub d: Vector3<f64>,
    pub d_dot: Vector3<f64>,
    pub length: f64,
}

/// A rigid contact as the model keeps it: centres in their body frames, a unit normal.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ContactData {
    Plane {
        body: usize,
        centre: Vector3<f64>,
        radius: f64,
        /// The plane's body (`None`: the ground), its point and unit normal in that body's frame.
        plane_body: Option<usize>,
        point: Vector3<f64>,
        normal: Vector3<f64>,
        /// Two unit tangents of the plane, with the normal a right-handed frame, in the plane's
        /// body's frame: the rows of its friction ([`crate::contact_friction`]).
        tangents: [Vector3<f64>; 2],
        /// Coulomb's coefficient, where the contact has friction.
        friction: Option<f64>,
    },
    Spheres {
        bodies: [Option<usize>; 2],
        centres: [Vector3<f64>; 2],
        radii: [f64; 2],
        /// The axis, in the first sphere's body's frame, across which the line of centres gives
        /// the tangents of the friction's rows ([`crate::contact_friction`]).
        helper: Vector3<f64>,
        /// Coulomb's coefficient, where the contact has friction.
        friction: Option<f64>,
    },
}

impl Model {
    /// The model with rigid sphere–plane contacts (after its joint limits, [`Model::with_limits`]).
    /// Errors name the contact.
    pub fn with_rigid_contacts(mut self, contacts: Vec<SpherePlaneContact>) -> Result<Self, ModelError> {
        let (q0, _) = self.initial_state();
        for c in contacts {
            let bad = |what: String| ModelError::InvalidParameter {
                element: format!("force '{}'", c.name),
                what,
            };
            if c.body >= self.bodies().len() {
                return Err(bad("the sphere must be on a moving body".into()));
            }
            if c.plane_body.is_some_and(|b| b >= self.bodies().len()) {
                return Err(bad("the plane's body is not in the model".into()));
            }
            if c.plane_body == Some(c.body) {
                return Err(bad("the sphere and the plane are on the same body".into()));
            }
            if !(c.radius.is_finite() && c.radius >= 0.0) {
                return Err(bad(format!("radius must be finite and ≥ 0, got {}", c.radius)));
            }
            let normal = Vector3::from(c.normal);
            let length = normal.norm();
            if !(length.is_finite() && length > 0.0 && c.point.iter().chain(&c.centre).all(|x| x.is_finite())) {
                return Err(bad(
                    "the plane's point and normal and the sphere's centre must be finite, the normal not zero".into(),
                ));
            }
            let spec = JointLimit::contact(&c.name, c.restitution, c.rest_speed);
            spec.check().map_err(bad)?;
            if let Some(mu) = c.friction.filter(|mu| !(mu.is_finite() && *mu >= 0.0)) {
                return Err(bad(format!("friction must be a coefficient ≥ 0, got {mu}")));
            }
            let f = self.frame(Some(c.body), &q0, &[]);
            let normal = normal / length;
            let fp = self.frame(c.plane_body, &q0, &[]);
            let tangents = crate::contact_friction::tangents(&normal).map(|t| fp.a.transpose() * t);
            let data = ContactData::Plane {
                body: c.body,
                centre: f.a.transpose() * (Vector3::from(c.centre) - f.r),
                radius: c.radius,
                plane_body: c.plane_body,
                point: fp.a.transpose() * (Vector3::from(c.point) - fp.r),
                normal: fp.a.transpose() * normal,
                tangents,
                friction: c.friction,
            };
            let gap = normal.dot(&(Vector3::from(c.centre) - Vector3::from(c.point))) - c.radius;
            if gap < -1e-12 {
                return Err(bad(format!("the sphere starts {:e} m into the plane", -gap)));
            }
            if c.friction.is_some() {
                self.friction_contacts.push(self.contacts.len());
            }
            self.limits.push(spec);
            self.contacts.push(data);
        }
        self.add_contact_frictions();
        Ok(self)
    }

    /// The model with rigid sphere–sphere contacts too (after [`Model::with_rigid_contacts`]).
    /// Errors name the contact.
    pub fn with_rigid_sphere_pairs(mut self, contacts: Vec<SphereSphereContact>) -> Result<Self, ModelError> {
        let (q0, _) = self.initial_state();
        for c in contacts {
            let bad = |what: String| ModelError::InvalidParameter {
                element: format!("force '{}'", c.name),
                what,
            };
            if c.bodies[0] == c.bodies[1] {
                return Err(bad("the two spheres must be on two different bodies".into()));
            }
            if c.bodies.iter().any(|b| b.is_some_and(|b| b >= self.bodies().len())) {
                return Err(bad("a sphere's body is not in the model".into()));
            }
            if !c.radii.iter().all(|r| r.is_finite() && *r >= 0.0) || !c.centres.iter().flatten().all(|x| x.is_finite())
            {
                return Err(bad(
                    "the spheres' centres and radii must be finite, the radii ≥ 0".into()
                ));
            }
            let spec = JointLimit::contact(&c.name, c.restitution, c.rest_speed);
            spec.check().map_err(bad)?;
            if let Some(mu) = c.friction.filter(|mu| !(mu.is_finite() && *mu >= 0.0)) {
                return Err(bad(format!("friction must be a coefficient ≥ 0, got {mu}")));
            }
            let local = |b: Option<usize>, p: [f64; 3]| {
                let f = self.frame(b, &q0, &[]);
                f.a.transpose() * (Vector3::from(p) - f.r)
            };
            let [ci, cj] = c.centres.map(Vector3::from);
            let gap = (cj - ci).norm() - c.radii[0] - c.radii[1];
            if gap < -1e-12 {
                return Err(bad(format!("the spheres start {:e} m into each other", -gap)));
            }
            // The line of centres in the first body's frame (any direction where they coincide).
            let line = self.frame(c.bodies[0], &q0, &[]).a.transpose() * (cj - ci);
            let line = if line.norm() > 0.0 { line } else { Vector3::z() };
            let data = ContactData::Spheres {
                bodies: c.bodies,
                centres: [local(c.bodies[0], c.centres[0]), local(c.bodies[1], c.centres[1])],
                radii: c.radii,
                helper: crate::contact_friction::least_along(&line),
                friction: c.friction,
            };
            if c.friction.is_some() {
                self.friction_contacts.push(self.contacts.len());
            }
            self.limits.push(spec);
            self.contacts.push(data);
        }
        self.add_contact_frictions();
        Ok(self)
    }

    /// Two spheres (centres in their bodies' frames) at `(q, v)`: their bodies' frames, the
    /// centres' global arms, the line of centres `d = c_j − c_i`, its rate and length.
    pub(crate) fn sphere_pair(
        &self,
        bodies: &[Option<usize>; 2],
        centres: &[Vector3<f64>; 2],
        q: &[f64],
        v: &[f64],
    ) -> SpherePair {
        let (fi, fj) = (self.frame(bodies[0], q, v), self.frame(bodies[1], q, v));
        let (si, sj) = (fi.a * centres[0], fj.a * centres[1]);
        let d = fj.r + sj - fi.r - si;
        SpherePair {
            d_dot: fj.point_velocity(&sj) - fi.point_velocity(&si),
            length: d.norm(),
            d,
            si,
            sj,
            fi,
            fj,
        }
    }

    /// Rigid contact `k`'s unit normal (the direction in which it pushes its body: a plane's
    /// sphere, or the second of two spheres) and its contact point at `q`, global: the sphere's
    /// point nearest the plane, or the first sphere's point towards the second.
    fn contact_geometry(&self, k: usize, q: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
        match &self.contacts[k] {
            ContactData::Plane {
                body,
                centre,
                radius,
                plane_body,
                normal,
                ..
            } => {
                let (fi, fj) = (self.frame(*plane_body, q, &[]), self.frame(Some(*body), q, &[]));
                let n = fi.a * normal;
                (n, fj.point(centre) - *radius * n)
            }
            ContactData::Spheres {
                bodies, centres, radii, ..
            } => {
                let p = self.sphere_pair(bodies, centres, q, &[]);
                let n = if p.length > 0.0 {
                    p.d / p.length
                } else {
                    Vector3::zeros()
                };
                (n, p.fi.r + p.si + radii[0] * n)
            }
        }
    }

    /// The number of rigid contacts (the last limits, after the joints').
    pub fn rigid_contact_count(&self) -> usize {
        self.contacts.len()
    }

    /// Each rigid contact's resultant at `q` into `out` (one per rigid contact, in order), with
    /// `limit_forces` the run's force of every limit (the joints' first, then the contacts') and
    /// `friction` its friction forces (the joints' first, then each cone's two): its gap, normal
    /// force, force on its body (`force · n` and the friction `F₁ t₁ + F₂ t₂`) and contact point
    /// ([`dalembert_system::ContactResultant`]).
    pub fn rigid_contact_resultants_into(
        &self,
        q: &[f64],
        (limit_forces, friction): (&[f64], &[f64]),
        out: &mut [ContactResultant<3>],
    ) {
        let first = self.limits.len() - self.contacts.len();
        let mut row = SlipRow::default();
        for (k, slot) in out.iter_mut().enumerate().take(self.contacts.len()) {
            let gap = self.contact_row_into(k, q, &[], &mut row);
            let (n, point) = self.contact_geometry(k, q);
            let force = limit_forces.get(first + k).copied().unwrap_or(0.0);
            let mut r = ContactResultant::new(gap);
            if force != 0.0 {
                r.add((force * n).into(), force, point.into());
            }
            *slot = r.finish(point.into());
        }
        let first = self.friction_joints.len();
        for (i, &c) in self.friction_contacts.iter().enumerate() {
            if let (Some(f), Some(slot)) = (friction.get(first + 2 * i..first + 2 * i + 2), out.get_mut(c)) {
                let force = self.contact_friction_force(i, q, (f[0], f[1]));
                slot.force.iter_mut().zip(force.iter()).for_each(|(x, y)| *x += y);
            }
        }
    }

    /// The gap row of rigid contact `k` (after the joint limits) at `(q, v)`, and the gap.
    fn contact_row_into(&self, k: usize, q: &[f64], v: &[f64], row: &mut SlipRow) -> f64 {
        row.clear();
        let mut push = |body: Option<usize>, lin: Vector3<f64>, ang: Vector3<f64>| {
            if let Some(b) = body {
                for (i, x) in lin.iter().chain(ang.iter()).enumerate() {
                    if *x != 0.0 {
                        row.push(NV * b + i, *x);
                    }
                }
            }
        };
        match &self.contacts[k] {
            ContactData::Plane {
                body,
                centre,
                radius,
                plane_body,
                point,
                normal,
                ..
            } => {
                // The gap is the centre's coordinate along the plane's normal less the radius:
                // the prismatic joint's value with the plane's body as `i` (its formulas above).
                let (fi, fj) = (self.frame(*plane_body, q, v), self.frame(Some(*body), q, v));
                let (si, sj) = (fi.a * point, fj.a * centre);
                let n = fi.a * normal;
                let n_dot = fi.w.cross(&n);
                let d = fj.r + sj - fi.r - si;
                push(Some(*body), n, fj.a.transpose() * sj.cross(&n));
                push(*plane_body, -n, fi.a.transpose() * n.cross(&(d + si)));
                let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
                let centripetal = fj.centripetal(&sj) - fi.centripetal(&si);
                row.bias = fi.w.cross(&n_dot).dot(&d) + 2.0 * n_dot.dot(&d_dot) + n.dot(&centripetal);
                n.dot(&d) - radius
            }
            ContactData::Spheres {
                bodies, centres, radii, ..
            } => {
                let reach = radii[0] + radii[1];
                let SpherePair {
                    fi,
                    fj,
                    si,
                    sj,
                    d,
                    d_dot,
                    length,
                } = self.sphere_pair(bodies, centres, q, v);
                if length <= f64::MIN_POSITIVE.sqrt() {
                    // Concentric: no direction to part along.
                    return -reach;
                }
                let n = d / length;
                push(bodies[1], n, fj.a.transpose() * sj.cross(&n));
                push(bodies[0], -n, -(fi.a.transpose() * si.cross(&n)));
                let along = n.dot(&d_dot);
                row.bias = n.dot(&(fj.centripetal(&sj) - fi.centripetal(&si)))
                    + (d_dot.norm_squared() - along * along) / length;
                length - reach
            }
        }
    }
}
