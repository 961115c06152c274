//! Torques about a revolute or cylindrical joint's axis: a joint torque `f(t)`, the rotational
//! spring–damper `τ = −k (θ − θ₀) − c θ̇`, and the servo
//! `τ = clamp(−k (θ − θ₀ − θ*(t)) − c θ̇ + f(t), τ_lo, τ_hi)` that follows a target angle `θ*(t)`
//! (an MJCF `position` or affine `general` actuator), acting `+τ z` on the joint's second body
//! and `−τ z` on its first.
//!
//! With the joint frame `(x_i, y_i, z)` on body `i` and `x_j` on body `j` (equal to `x_i` in the
//! initial configuration), the joint angle is `θ = atan2(x_j · y_i, x_j · x_i)` (right-handed about
//! `z`, 0 initially) and its rate `θ̇ = z · (ω_j − ω_i)`. The angle is known only within ±π: the
//! spring's deflection `θ − θ₀` is taken in (−π, π], and the model stops a run whose
//! spring winds past [`WIND_LIMIT`] rather than let the torque jump at half a turn.

use super::add_torque;
use crate::frame::Frame;
use crate::joints::second_derivatives::{skew, WrenchDerivative};
use crate::joints::JointData;
use dalembert_system::AxisLaw;
use nalgebra::Matrix3;
use nalgebra::Vector3;
use std::f64::consts::{PI, TAU};

type V3 = Vector3<f64>;

/// The largest deflection `|θ − θ₀|` (rad) a rotational spring may reach: 0.9 π. A step of an
/// explicit method turns a joint by far less than the remaining 0.1 π (18°) in any run that
/// resolves its motion, so the run stops before the measured angle can wrap.
pub const WIND_LIMIT: f64 = 0.9 * PI;

/// A torque law about a joint axis (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct AxisForce {
    body_i: Option<usize>,
    body_j: Option<usize>,
    /// The joint frame's `x, y, z` on body `i` (body components).
    x_i: V3,
    y_i: V3,
    z_i: V3,
    /// The joint frame's `x` on body `j` (body components).
    x_j: V3,
    /// The law (shared with joint coordinates).
    law: AxisLaw,
    /// The joint's index in the model.
    joint: usize,
}

impl AxisForce {
    /// The moving bodies the torque acts between.
    pub fn bodies(&self) -> Vec<usize> {
        self.body_i.into_iter().chain(self.body_j).collect()
    }

    /// The law about `joint`'s axis.
    pub fn new(joint: (usize, &JointData), law: AxisLaw) -> Self {
        let (index, joint) = joint;
        let col = |k: usize| -> V3 { joint.axes_i.column(k).into() };
        AxisForce {
            body_i: joint.body_i,
            body_j: joint.body_j,
            x_i: col(0),
            y_i: col(1),
            z_i: col(2),
            x_j: joint.axes_j.column(0).into(),
            law,
            joint: index,
        }
    }

    /// The joint's index in the model, and the law (for joint coordinates).
    pub fn joint_law(&self) -> (usize, &AxisLaw) {
        (self.joint, &self.law)
    }

    /// The joint angle `θ` (right-handed about `z`, 0 in the initial configuration, within ±π).
    fn angle(&self, fi: &Frame, fj: &Frame) -> f64 {
        let xj = fj.a * self.x_j;
        xj.dot(&(fi.a * self.y_i)).atan2(xj.dot(&(fi.a * self.x_i)))
    }

    /// The joint angle at the state behind `frame`.
    pub fn angle_at(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        self.angle(&frame(self.body_i), &frame(self.body_j))
    }

    /// The axis (global), the deflection `θ − θ₀ − θ*(t)` in (−π, π] and the rate `θ̇`.
    fn state(&self, t: f64, fi: &Frame, fj: &Frame) -> (V3, f64, f64) {
        let z = fi.a * self.z_i;
        let deflection = (self.angle(fi, fj) - self.law.free(t) + PI).rem_euclid(TAU) - PI;
        (z, deflection, z.dot(&(fj.w - fi.w)))
    }

    /// Adds `+τ z` on body `j` and `−τ z` on body `i` at time `t`.
    pub fn add(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let (fi, fj) = (frame(self.body_i), frame(self.body_j));
        let (z, deflection, rate) = self.state(t, &fi, &fj);
        let (tau, _) = self.law.torque(t, deflection, rate);
        if let Some(b) = self.body_j {
            add_torque(out, b, &fj, &(tau * z));
        }
        if let Some(b) = self.body_i {
            add_torque(out, b, &fi, &(-tau * z));
        }
    }

    /// `½ k (θ − θ₀)²`; zero for a servo (its torque, held within its range, has no potential:
    /// its whole work is counted as work done on the model).
    pub fn potential(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let (_, deflection, _) = self.state(t, &frame(self.body_i), &frame(self.body_j));
        self.law.potential(deflection)
    }

    /// No damping, no applied torque, not a servo.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }

    /// A spring wound past [`WIND_LIMIT`] is an error (its angle would wrap).
    pub fn check(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> Result<(), String> {
        if self.law.stiffness == 0.0 {
            return Ok(());
        }
        let (_, deflection, _) = self.state(t, &frame(self.body_i), &frame(self.body_j));
        if deflection.abs() > WIND_LIMIT {
            let from = if self.law.target.is_some() {
                "its target"
            } else {
                "its free angle"
            };
            return Err(format!(
                "joint turned {deflection:.4} rad from {from}: the angle is measured within ±π, so the law cannot follow past 0.9π"
            ));
        }
        Ok(())
    }
}

impl AxisForce {
    /// `T_j = τ z = −T_i`, `τ = −k (θ − θ₀) − c θ̇ + f(t)`, `z = A_i z'`: with `a = x_j·x_i`,
    /// `b = x_j·y_i`, `∂θ/∂θ_j = (a x_j×y_i − b x_j×x_i)/(a² + b²) = −∂θ/∂θ_i`; `θ̇ = z·(ω_j − ω_i)`
    /// has `∂θ̇/∂θ_i = z × ω_j`, `∂θ̇/∂θ_j = ω_j × z`, `∂θ̇/∂ω_j = z = −∂θ̇/∂ω_i`; `∂z/∂θ_i = −[z]×`.
    pub(crate) fn wrench_derivative(
        &self,
        t: f64,
        frame: &dyn Fn(Option<usize>) -> Frame,
    ) -> ([Option<usize>; 2], WrenchDerivative) {
        let (fi, fj) = (frame(self.body_i), frame(self.body_j));
        let (z, deflection, rate) = self.state(t, &fi, &fj);
        let (tau, inside) = self.law.torque(t, deflection, rate);
        // Held at a bound of its range, the torque does not change with the state.
        let (k, c) = if inside {
            (self.law.stiffness, self.law.damping)
        } else {
            (0.0, 0.0)
        };
        let xj = fj.a * self.x_j;
        let (xi, yi) = (fi.a * self.x_i, fi.a * self.y_i);
        let (a, b) = (xj.dot(&xi), xj.dot(&yi));
        let g_theta_j: V3 = (xj.cross(&yi) * a - xj.cross(&xi) * b) / (a * a + b * b);
        // Rows ∂τ/∂x for the columns r_i, θ_i, r_j, θ_j.
        let zero = V3::zeros();
        let dtau = [
            zero,
            -(-g_theta_j) * k - z.cross(&fj.w) * c,
            zero,
            -g_theta_j * k - fj.w.cross(&z) * c,
        ];
        let dtau_v = [zero, z * c, zero, -z * c];
        let tj = z * tau;
        let mut w = WrenchDerivative::zero();
        w.torque = [-tj, tj];
        for col in 0..4 {
            let dz = if col == 1 { -skew(&z) } else { Matrix3::zeros() };
            let dtj = z * dtau[col].transpose() + dz * tau;
            w.d[3][col] = dtj;
            w.d[1][col] = -dtj;
            let dtj_v = z * dtau_v[col].transpose();
            w.dv[3][col] = dtj_v;
            w.dv[1][col] = -dtj_v;
        }
        ([self.body_i, self.body_j], w)
    }
}
