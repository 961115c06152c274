//! Joint reactions from the multipliers (`docs/sign-conventions.md`, spatial section).
//!
//! With `M v̇ + C_qᵀ λ = Q`, the generalized force a joint applies to body `b` is `−C_q,bᵀ λ`: on the
//! velocity coordinates `(ṙ, ω)` (global angular velocity) it is the force `F` on the body and the
//! moment `n` about its centre of mass, global components. A joint's reaction is **what its second
//! body exerts on its first body**: `F_i` and the moment about the joint's point `P` on body `i`,
//! `M_P = n_i − (P − r_i) × F_i`. When the first body is the ground, the reaction is computed on the
//! second body and reversed (`F = −F_j`, `M_P = −(n_j + (r_j − P) × F_j)`).

use crate::frame::NV;
use crate::joints::primitives::Row;
use crate::model::Model;
use dalembert_system::SlipRow;
use nalgebra::{Matrix3, Vector3};

/// A joint's reaction: force and moment that its second body exerts on its first body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reaction {
    /// Force (global components).
    pub force: Vector3<f64>,
    /// Moment about [`Reaction::point`] (global components).
    pub moment: Vector3<f64>,
    /// The joint's point on the first body (global).
    pub point: Vector3<f64>,
    /// The joint frame's axes `x, y, z` (columns, global components); `z` is the joint axis.
    pub axes: Matrix3<f64>,
}

impl Reaction {
    /// Force and moment in the joint frame's components (`z` along the joint axis).
    pub fn in_joint_axes(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.axes.transpose() * self.force, self.axes.transpose() * self.moment)
    }
}

impl Model {
    /// The reaction of every joint at `(t, q, λ)` (`λ` from a formulation or inverse dynamics), in
    /// joint order (drivers excluded: [`Model::driver_efforts`]). `lambda` has one entry per
    /// constraint equation.
    pub fn reactions(&self, t: f64, q: &[f64], lambda: &[f64]) -> Vec<Reaction> {
        let zero = Reaction {
            force: Vector3::zeros(),
            moment: Vector3::zeros(),
            point: Vector3::zeros(),
            axes: Matrix3::identity(),
        };
        let mut out = vec![zero; self.joints().len()];
        self.reactions_into(t, q, lambda, &mut out);
        out
    }

    /// [`Model::reactions`] into `out` (one entry per joint), without allocating.
    pub fn reactions_into(&self, t: f64, q: &[f64], lambda: &[f64], out: &mut [Reaction]) {
        assert_eq!(out.len(), self.joints().len(), "one reaction per joint");
        let mut row = 0;
        let mut rows = [Row::default(); 3];
        for (j, slot) in self.joints().iter().zip(out.iter_mut()) {
            let (fi, fj) = (self.frame(j.body_i, q, &[]), self.frame(j.body_j, q, &[]));
            // Σ λ_r × (row on i), Σ λ_r × (row on j): the generalized constraint forces with a minus.
            let mut sums = [[Vector3::zeros(); 2]; 2];
            for prim in &j.primitives {
                let n = prim.len();
                prim.evaluate(t, &fi, &fj, &mut rows[..n]);
                for r in &rows[..n] {
                    let l = lambda[row];
                    for k in 0..2 {
                        sums[0][k] += l * r.i[k];
                        sums[1][k] += l * r.j[k];
                    }
                    row += 1;
                }
            }
            let point = fi.point(&j.point_i);
            let (force, moment) = if j.body_i.is_some() {
                let (f, n) = (-sums[0][0], -sums[0][1]);
                (f, n - (point - fi.r).cross(&f))
            } else {
                let (f, n) = (-sums[1][0], -sums[1][1]);
                (-f, -(n + (fj.r - point).cross(&f)))
            };
            *slot = Reaction {
                force,
                moment,
                point,
                axes: fi.a * j.axes_i,
            };
        }
    }

    /// Adds to the reactions (`out`, one per joint, from [`Model::reactions_into`]) the stops'
    /// and friction's forces along their joints: `limit[k]` along limited joint `k`'s value,
    /// `friction[k]` along friction joint `k`'s (each the force or torque on the second body along
    /// the joint, `docs/limits.md`, `docs/friction.md`), so that a joint's reaction is all that
    /// its second body exerts on its first through it. Allocates nothing.
    pub fn add_joint_forces_into(&self, q: &[f64], limit: &[f64], friction: &[f64], out: &mut [Reaction]) {
        let mut row = SlipRow::default();
        let along = self
            .limited_joints
            .iter()
            .zip(limit)
            .chain(self.friction_joints.iter().zip(friction));
        for (&joint, &force) in along {
            if force == 0.0 {
                continue;
            }
            self.joint_row_into(joint, q, &[], &mut row);
            let j = &self.joints()[joint];
            // The generalized force g F on the body whose side the reaction is taken on: its
            // force (global) and its moment (body frame, turned to global).
            let side = j.body_i.or(j.body_j);
            let Some(b) = side else { continue };
            let frame = self.frame(Some(b), q, &[]);
            let (mut f, mut m) = (Vector3::zeros(), Vector3::zeros());
            for &(i, g) in row.entries() {
                match i.checked_sub(NV * b) {
                    Some(c @ 0..=2) => f[c] += g * force,
                    Some(c @ 3..=5) => m[c - 3] += g * force,
                    _ => {}
                }
            }
            let n = frame.a * m;
            let slot = &mut out[joint];
            if j.body_i.is_some() {
                slot.force += f;
                slot.moment += n - (slot.point - frame.r).cross(&f);
            } else {
                slot.force -= f;
                slot.moment -= n + (frame.r - slot.point).cross(&f);
            }
        }
    }
}
