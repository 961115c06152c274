//! Coulomb friction in a rigid sphere–plane or sphere–sphere contact (`docs/limits.md`,
//! "Friction in spatial rigid contact"): a friction cone, two friction elements of the seam
//! ([`dalembert_system::JointFriction::cone`]) whose rows are the slip velocity of body `j`'s
//! material point at the contact point `P` over body `i`'s, along two unit tangents `t₁`, `t₂`
//! of the plane of contact, loaded by the contact's normal force.
//!
//! With the arms `a_j = P − r_j`, `a_i = P − r_i`, and `Ṗ` the rate of the contact point (a
//! point of the geometry, not of either body):
//!
//! ```text
//! w = t·(ṙ_j + ω_j × a_j − ṙ_i − ω_i × a_i)
//! g: ṙ_j ↦ t,  ω'_j ↦ A_jᵀ (a_j × t),  ṙ_i ↦ −t,  ω'_i ↦ −A_iᵀ (a_i × t)
//! b = ṫ·Δv + t·(ω_j × (Ṗ − ṙ_j) − ω_i × (Ṗ − ṙ_i))
//! ```
//!
//! `Δv` the slip velocity (the bracket of `w`); `b` is `ẇ` at zero accelerations. On a plane
//! (body `i`, the sphere on `j`, centre `c`, radius `R`, normal `n`): `P = c − R n`,
//! `Ṗ = ċ − R ω_i × n`, and the tangents are fixed in the plane's body, `ṫ = ω_i × t`. Between
//! two spheres (centres `c_i`, `c_j`, radii `R_i`, `R_j`, `d = c_j − c_i`, `n = d / |d|`):
//! `P = c_i + R_i n`, `ṅ = (ḋ − n (n·ḋ)) / |d|`, `Ṗ = ċ_i + R_i ṅ`, and the tangents turn
//! with the line of centres, across an axis `h` fixed in body `i` (`ḣ = ω_i × h`):
//!
//! ```text
//! u = h × n,  t₁ = u / |u|,  t₂ = n × t₁
//! ṫ₁ = (u̇ − t₁ (t₁·u̇)) / |u|,  u̇ = ḣ × n + h × ṅ;   ṫ₂ = ṅ × t₁ + n × ṫ₁
//! ```
//!
//! `h` is the axis of body `i`'s frame least along the line of centres where the model is built,
//! so the tangents turn smoothly unless the line of centres turns to within 10⁻⁹ rad of it.

use crate::frame::NV;
use crate::limits::{ContactData, SpherePair};
use crate::Model;
use dalembert_system::{JointFriction, SlipRow};
use nalgebra::Vector3;

/// The slip speed (m/s) within which a rigid contact's friction counts as stuck.
pub const STICK_SPEED: f64 = 1e-6;

/// The coordinate axis least along `n` (the first of equals).
pub(crate) fn least_along(n: &Vector3<f64>) -> Vector3<f64> {
    (0..3)
        .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .map_or(Vector3::x(), |a| Vector3::ith(a, 1.0))
}

/// Two unit tangents `t₁`, `t₂` of the plane of unit normal `n`, with `(t₁, t₂, n)`
/// right-handed: `t₁` across `n` and the coordinate axis least along it. The friction law is
/// the same in any pair of tangents (it bounds and directs the force by its norm), so the choice
/// changes a result only at round-off.
pub(crate) fn tangents(n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let t1 = least_along(n).cross(n).normalize();
    [t1, n.cross(&t1)]
}

/// The smallest `|h × n|` for which the tangents of a sphere pair are taken across `h`: nearer,
/// across the coordinate axis least along `n` ([`tangents`]; they then jump about `n`, which
/// the law, reading the slip's size and direction in the plane, does not see).
const HELPER_MIN: f64 = 1e-9;

impl Model {
    /// The joints' friction elements, then each rigid contact's cone: its two tangent rows,
    /// loaded by the contact's normal force (the limit after the joint limits).
    pub(crate) fn add_contact_frictions(&mut self) {
        self.frictions.truncate(self.friction_joints.len());
        let first = self.frictions.len();
        for (i, &c) in self.friction_contacts.iter().enumerate() {
            let (ContactData::Plane { friction: Some(mu), .. } | ContactData::Spheres { friction: Some(mu), .. }) =
                self.contacts[c]
            else {
                continue;
            };
            let name = self.limits[self.limited_joints.len() + c].name.clone();
            for row in 0..2 {
                self.frictions.push(JointFriction {
                    element: "contact",
                    name: name.clone(),
                    coefficient: mu,
                    viscous: 0.0,
                    constant: 0.0,
                    load_rows: Vec::new(),
                    load_limit: Some(self.limited_joints.len() + c),
                    stick_speed: STICK_SPEED,
                    cone: Some(first + 2 * i + 1 - row),
                });
            }
        }
    }

    /// Cone `i`'s contact at `(q, v)` (global): its bodies, the arms of its contact point, the
    /// point's rate, its tangents and their rates (the formulas above).
    fn cone_geometry(&self, i: usize, q: &[f64], v: &[f64]) -> Option<ConeGeometry> {
        match &self.contacts[*self.friction_contacts.get(i)?] {
            ContactData::Plane {
                body,
                centre,
                radius,
                plane_body,
                normal,
                tangents,
                ..
            } => {
                let (fi, fj) = (self.frame(*plane_body, q, v), self.frame(Some(*body), q, v));
                let n = fi.a * normal;
                let sj = fj.a * centre;
                let t = tangents.map(|t| fi.a * t);
                Some(ConeGeometry {
                    bodies: [*plane_body, Some(*body)],
                    arm_j: sj - *radius * n,
                    arm_i: fj.r + sj - *radius * n - fi.r,
                    point_rate: fj.point_velocity(&sj) - *radius * fi.w.cross(&n),
                    t,
                    t_dot: t.map(|t| fi.w.cross(&t)),
                    fi,
                    fj,
                })
            }
            ContactData::Spheres {
                bodies,
                centres,
                radii,
                helper,
                ..
            } => {
                let SpherePair {
                    fi,
                    fj,
                    si,
                    d,
                    d_dot,
                    length,
                    ..
                } = self.sphere_pair(bodies, centres, q, v);
                if length <= f64::MIN_POSITIVE.sqrt() {
                    // Concentric: no plane of contact.
                    return None;
                }
                let n = d / length;
                let n_dot = (d_dot - n * n.dot(&d_dot)) / length;
                let h = fi.a * helper;
                let u = h.cross(&n);
                let (t, t_dot) = if u.norm() >= HELPER_MIN {
                    let size = u.norm();
                    let t1 = u / size;
                    let u_dot = fi.w.cross(&h).cross(&n) + h.cross(&n_dot);
                    let t1_dot = (u_dot - t1 * t1.dot(&u_dot)) / size;
                    ([t1, n.cross(&t1)], [t1_dot, n_dot.cross(&t1) + n.cross(&t1_dot)])
                } else {
                    let [t1, t2] = tangents(&n);
                    // Turning with `n` about the axis across both (`ṫ = Ω × t`, `Ω = n × ṅ`).
                    let spin = n.cross(&n_dot);
                    ([t1, t2], [spin.cross(&t1), spin.cross(&t2)])
                };
                let arm_i = si + radii[0] * n;
                Some(ConeGeometry {
                    bodies: *bodies,
                    arm_j: fi.r + arm_i - fj.r,
                    arm_i,
                    point_rate: fi.point_velocity(&si) + radii[0] * n_dot,
                    t,
                    t_dot,
                    fi,
                    fj,
                })
            }
        }
    }

    /// The row of the `i`-th contact friction element (after the joints'; cone `i / 2`, tangent
    /// `i % 2`) at `(q, v)` into `row` (the formulas above).
    pub(crate) fn tangent_row_into(&self, i: usize, q: &[f64], v: &[f64], row: &mut SlipRow) {
        row.clear();
        let Some(c) = self.cone_geometry(i / 2, q, v) else {
            return;
        };
        let t = c.t[i % 2];
        let mut push = |body: Option<usize>, lin: Vector3<f64>, ang: Vector3<f64>| {
            if let Some(b) = body {
                for (k, x) in lin.iter().chain(ang.iter()).enumerate() {
                    if *x != 0.0 {
                        row.push(NV * b + k, *x);
                    }
                }
            }
        };
        push(c.bodies[1], t, c.fj.a.transpose() * c.arm_j.cross(&t));
        push(c.bodies[0], -t, -(c.fi.a.transpose() * c.arm_i.cross(&t)));
        if v.is_empty() {
            return;
        }
        let slip = c.fj.point_velocity(&c.arm_j) - c.fi.point_velocity(&c.arm_i);
        let p = c.point_rate;
        row.bias = c.t_dot[i % 2].dot(&slip) + t.dot(&(c.fj.w.cross(&(p - c.fj.v)) - c.fi.w.cross(&(p - c.fi.v))));
    }

    /// The friction force `F₁ t₁ + F₂ t₂` (global, on body `j`: the sphere on a plane, the second
    /// of two spheres) of cone `i` at `q`,
    /// from its two elements' forces `f`.
    pub(crate) fn contact_friction_force(&self, i: usize, q: &[f64], f: (f64, f64)) -> Vector3<f64> {
        self.cone_geometry(i, q, &[])
            .map_or(Vector3::zeros(), |g| f.0 * g.t[0] + f.1 * g.t[1])
    }
}

/// What [`Model::cone_geometry`] finds.
struct ConeGeometry {
    /// Bodies `i` and `j` (`None`: the ground).
    bodies: [Option<usize>; 2],
    /// `a_j = P − r_j`, `a_i = P − r_i`, `Ṗ`.
    arm_j: Vector3<f64>,
    arm_i: Vector3<f64>,
    point_rate: Vector3<f64>,
    /// `t₁`, `t₂` and their rates.
    t: [Vector3<f64>; 2],
    t_dot: [Vector3<f64>; 2],
    fi: crate::frame::Frame,
    fj: crate::frame::Frame,
}
