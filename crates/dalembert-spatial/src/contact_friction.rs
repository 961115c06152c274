//! Coulomb friction in a rigid sphere–plane contact (`docs/limits.md`, "Friction in spatial
//! rigid contact"): a friction cone, two friction elements of the seam
//! ([`dalembert_system::JointFriction::cone`]) whose rows are the slip velocity of the sphere's
//! material point at the contact over the plane's, along two tangents `t₁`, `t₂` of the plane
//! (fixed in the plane's body), loaded by the contact's normal force.
//!
//! With the plane on body `i` (the ground: at rest), the sphere on body `j`, its centre
//! `c = r_j + s_j`, the normal `n`, the contact point `P = c − R n` and its arms
//! `a_j = P − r_j`, `a_i = P − r_i`:
//!
//! ```text
//! w = t·(ṙ_j + ω_j × a_j − ṙ_i − ω_i × a_i)
//! g: ṙ_j ↦ t,  ω'_j ↦ A_jᵀ (a_j × t),  ṙ_i ↦ −t,  ω'_i ↦ −A_iᵀ (a_i × t)
//! b = ṫ·Δv + t·(ω_j × (Ṗ − ṙ_j) − ω_i × (Ṗ − ṙ_i)),   ṫ = ω_i × t,  Ṗ = ċ − R ω_i × n
//! ```
//!
//! `Δv` the slip velocity (the bracket of `w`); `b` is `ẇ` at zero accelerations (`P` moves
//! along the plane as the sphere rolls, so the arms change at `Ṗ − ṙ`).

use crate::frame::NV;
use crate::limits::ContactData;
use crate::Model;
use dalembert_system::{JointFriction, SlipRow};
use nalgebra::Vector3;

/// The slip speed (m/s) within which a rigid contact's friction counts as stuck.
pub const STICK_SPEED: f64 = 1e-6;

/// Two unit tangents `t₁`, `t₂` of the plane of unit normal `n`, with `(t₁, t₂, n)`
/// right-handed: `t₁` across `n` and the coordinate axis least along it. The friction law is
/// the same in any pair of tangents (it bounds and directs the force by its norm), so the choice
/// changes a result only at round-off.
pub(crate) fn tangents(n: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let axis = (0..3)
        .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .map_or(Vector3::x(), |a| Vector3::ith(a, 1.0));
    let t1 = axis.cross(n).normalize();
    [t1, n.cross(&t1)]
}

impl Model {
    /// The joints' friction elements, then each rigid contact's cone: its two tangent rows,
    /// loaded by the contact's normal force (the limit after the joint limits).
    pub(crate) fn add_contact_frictions(&mut self) {
        self.frictions.truncate(self.friction_joints.len());
        let first = self.frictions.len();
        for (i, &c) in self.friction_contacts.iter().enumerate() {
            let ContactData::Plane { friction: Some(mu), .. } = self.contacts[c] else {
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

    /// The contact point, the sphere's body, its arm `a_j` and the unit tangents of cone `i`'s
    /// contact at `q` (global), with the plane's frame.
    fn cone_geometry(&self, i: usize, q: &[f64], v: &[f64]) -> Option<ConeGeometry> {
        let ContactData::Plane {
            body,
            centre,
            radius,
            plane_body,
            normal,
            tangents,
            ..
        } = &self.contacts[*self.friction_contacts.get(i)?]
        else {
            return None;
        };
        let (fi, fj) = (self.frame(*plane_body, q, v), self.frame(Some(*body), q, v));
        let n = fi.a * normal;
        let sj = fj.a * centre;
        Some(ConeGeometry {
            body: *body,
            plane_body: *plane_body,
            arm_j: sj - *radius * n,
            arm_i: fj.r + sj - *radius * n - fi.r,
            centre_arm: sj,
            radius: *radius,
            n,
            t: tangents.map(|t| fi.a * t),
            fi,
            fj,
        })
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
        push(Some(c.body), t, c.fj.a.transpose() * c.arm_j.cross(&t));
        push(c.plane_body, -t, -(c.fi.a.transpose() * c.arm_i.cross(&t)));
        if v.is_empty() {
            return;
        }
        let slip = c.fj.point_velocity(&c.arm_j) - c.fi.point_velocity(&c.arm_i);
        let point_rate = c.fj.point_velocity(&c.centre_arm) - c.radius * c.fi.w.cross(&c.n);
        let t_dot = c.fi.w.cross(&t);
        row.bias =
            t_dot.dot(&slip) + t.dot(&(c.fj.w.cross(&(point_rate - c.fj.v)) - c.fi.w.cross(&(point_rate - c.fi.v))));
    }

    /// The friction force `F₁ t₁ + F₂ t₂` (global, on the sphere's body) of cone `i` at `q`,
    /// from its two elements' forces `f`.
    pub(crate) fn contact_friction_force(&self, i: usize, q: &[f64], f: (f64, f64)) -> Vector3<f64> {
        self.cone_geometry(i, q, &[])
            .map_or(Vector3::zeros(), |g| f.0 * g.t[0] + f.1 * g.t[1])
    }
}

/// What [`Model::cone_geometry`] finds.
struct ConeGeometry {
    body: usize,
    plane_body: Option<usize>,
    /// `a_j = P − r_j`, `a_i = P − r_i`, `s_j = c − r_j`.
    arm_j: Vector3<f64>,
    arm_i: Vector3<f64>,
    centre_arm: Vector3<f64>,
    radius: f64,
    n: Vector3<f64>,
    t: [Vector3<f64>; 2],
    fi: crate::frame::Frame,
    fj: crate::frame::Frame,
}
