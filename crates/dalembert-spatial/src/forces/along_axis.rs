//! A force along a prismatic joint's axis by the law the joint torques and servos have
//! ([`AxisLaw`]): `F = clamp(−k (s − s₀ − s*(t)) − c ṡ + f(t), F_lo, F_hi)` with `s` the joint's
//! displacement (0 in the initial configuration) and `ṡ` its rate, `+F` along the axis on the
//! joint's second body and `−F` on its first. Its generalized force is `F` times the row of the
//! displacement's rate (`ṡ = g · v`, the joint-value row the couplings and limits use), so its
//! virtual work is `F δs` whatever the bodies' poses.

use crate::couplings::joint_value_row;
use crate::frame::{Frame, NV};
use crate::joints::second_derivatives::{skew, WrenchDerivative};
use crate::joints::JointData;
use dalembert_system::AxisLaw;
use nalgebra::{Matrix3, Vector3};

type V3 = Vector3<f64>;
type M3 = Matrix3<f64>;

/// The law along a prismatic joint (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct SlideForce {
    joint: JointData,
    /// The joint's index in the model.
    index: usize,
    law: AxisLaw,
}

impl SlideForce {
    /// The law along `joint`'s axis (`joint`: its index in the model and its data).
    pub fn new(joint: (usize, &JointData), law: AxisLaw) -> Self {
        SlideForce {
            joint: joint.1.clone(),
            index: joint.0,
            law,
        }
    }

    /// The moving bodies the force acts between.
    pub fn bodies(&self) -> Vec<usize> {
        self.joint.body_i.into_iter().chain(self.joint.body_j).collect()
    }

    /// The joint's index in the model, and the law (for joint coordinates).
    pub fn joint_law(&self) -> (usize, &AxisLaw) {
        (self.index, &self.law)
    }

    /// The displacement at the state behind `frame`.
    pub fn displacement_at(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        joint_value_row(&self.joint, &frame(self.joint.body_i), &frame(self.joint.body_j))
            .0
            .c
    }

    /// Adds `F` times the displacement's rate row at `t`.
    pub fn add(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let (fi, fj) = (frame(self.joint.body_i), frame(self.joint.body_j));
        let (row, rate) = joint_value_row(&self.joint, &fi, &fj);
        let (force, _) = self.law.torque(t, row.c - self.law.free(t), rate);
        for (body, f, g) in [(self.joint.body_i, &fi, row.i), (self.joint.body_j, &fj, row.j)] {
            let Some(b) = body else { continue };
            // The rotation part on the body-frame angular velocity: ∂/∂ω' = (∂/∂ω) A.
            let turn = f.a.transpose() * g[1];
            for k in 0..3 {
                out[NV * b + k] += force * g[0][k];
                out[NV * b + 3 + k] += force * turn[k];
            }
        }
    }

    /// The ends and the wrench derivatives (`crate::forces::jacobians`) at time `t` and the
    /// state behind `frame`.
    ///
    /// The force is `F z` on the second body and `−F z` on the first, both at the second body's
    /// joint point `P = r_j + s_j`, with `z` fixed on the first body and
    /// `F(s, ṡ)`, `s = z · d`, `d = P − r_i − s_i`, `ṡ = ż · d + z · ḋ`. So
    /// `∂s = zᵀ ∂d + dᵀ ∂z` and `∂ṡ = dᵀ ∂ż + żᵀ ∂d + ḋᵀ ∂z + zᵀ ∂ḋ` over the columns
    /// `r_i, θ_i, r_j, θ_j` (`z`, `ż = ω_i × z` and `ω_i × s_i` turn with body `i`,
    /// `s_j` and `ω_j × s_j` with body `j`), and `∂ṡ/∂(v_i, ω_i, v_j, ω_j) =
    /// (−z, z × (d + s_i), z, s_j × z)`, the joint-value row. Held at a bound of its range, `F`
    /// does not change with the state.
    pub(crate) fn wrench_derivative(
        &self,
        t: f64,
        frame: &dyn Fn(Option<usize>) -> Frame,
    ) -> ([Option<usize>; 2], WrenchDerivative) {
        let j = &self.joint;
        let (fi, fj) = (frame(j.body_i), frame(j.body_j));
        let (row, rate) = joint_value_row(j, &fi, &fj);
        let (force, inside) = self.law.torque(t, row.c - self.law.free(t), rate);
        let (k, c) = if inside {
            (self.law.stiffness, self.law.damping)
        } else {
            (0.0, 0.0)
        };
        let z = fi.a * j.axes_i.column(2);
        let (si, sj) = (fi.a * j.point_i, fj.a * j.point_j);
        let d = fj.r + sj - fi.r - si;
        let z_dot = fi.w.cross(&z);
        let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
        let zero = M3::zeros();
        // Columns r_i, θ_i, r_j, θ_j.
        let dz = [zero, -skew(&z), zero, zero];
        let dz_dot = [zero, -skew(&z_dot), zero, zero];
        let dd = [-M3::identity(), skew(&si), M3::identity(), -skew(&sj)];
        let dd_dot = [zero, skew(&fi.w.cross(&si)), zero, -skew(&fj.w.cross(&sj))];
        // The arm of the first body's force: `P − r_i = d + s_i`.
        let arm_i = d + si;
        let d_arm_i = [-M3::identity(), zero, M3::identity(), -skew(&sj)];
        let d_sj = [zero, zero, zero, -skew(&sj)];
        // Columns v_i, ω_i, v_j, ω_j: the joint-value row.
        let rate_v: [V3; 4] = [-z, z.cross(&arm_i), z, sj.cross(&z)];
        let fj_force = z * force;
        let mut w = WrenchDerivative::zero();
        w.torque = [arm_i.cross(&-fj_force), sj.cross(&fj_force)];
        for col in 0..4 {
            let ds = z.transpose() * dd[col] + d.transpose() * dz[col];
            let ds_dot = d.transpose() * dz_dot[col]
                + z_dot.transpose() * dd[col]
                + d_dot.transpose() * dz[col]
                + z.transpose() * dd_dot[col];
            let dforce = ds * -k - ds_dot * c;
            // ∂(F z) on the second body; the first body's force is its negative.
            let dfj = z * dforce + dz[col] * force;
            w.d[2][col] = dfj;
            w.d[3][col] = -skew(&fj_force) * d_sj[col] + skew(&sj) * dfj;
            w.d[0][col] = -dfj;
            w.d[1][col] = skew(&fj_force) * d_arm_i[col] - skew(&arm_i) * dfj;
            let dfj_v = z * (rate_v[col].transpose() * -c);
            w.dv[2][col] = dfj_v;
            w.dv[3][col] = skew(&sj) * dfj_v;
            w.dv[0][col] = -dfj_v;
            w.dv[1][col] = -skew(&arm_i) * dfj_v;
        }
        ([j.body_i, j.body_j], w)
    }

    /// `½ k (s − s₀)²`; zero for a servo.
    pub fn potential(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        self.law.potential(self.displacement_at(frame) - self.law.free(t))
    }

    /// No damping, no applied force, not a servo.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }
}
