//! The force elements' Jacobians for the analytic tangent of implicit integrators, in the wrench
//! form of [`WrenchDerivative`]: global forces `F` and torques `T` on the two ends and their
//! derivatives with respect to the ends' global displacements `r`, small global rotations `θ`
//! (`∂s/∂θ = −[s]×` for a body-fixed global vector `s`; the global angular velocity `ω = A ω'` at
//! fixed `ω'` turns with the body, so `∂(ω × s)/∂θ = −[ω × s]×`), velocities `v` and angular
//! velocities `ω`.

use super::{components, ForceData, ForceFrame};
use crate::frame::Frame;
use crate::joints::second_derivatives::{skew, WrenchDerivative};
use nalgebra::Matrix3;

type M3 = Matrix3<f64>;

impl ForceData {
    /// The element's ends (`[i, j]`, `None` for the ground or no second end) and its wrench
    /// derivatives at time `t` and the state behind `frame`; `None` when it has none (a
    /// user-written force, or a spring whose ends coincide).
    pub(crate) fn wrench_derivative(
        &self,
        t: f64,
        frame: &dyn Fn(Option<usize>) -> Frame,
    ) -> Option<([Option<usize>; 2], WrenchDerivative)> {
        match self {
            ForceData::PointForce {
                body,
                point,
                force,
                frame: axes,
            } => {
                // F = f (global) or A f' (body axes: ∂F/∂θ = −[F]×); T = s × F.
                let f = frame(Some(*body));
                let c = components(force, t);
                let (force, df) = match axes {
                    ForceFrame::Global => (c, M3::zeros()),
                    ForceFrame::Body => {
                        let g = f.a * c;
                        (g, -skew(&g))
                    }
                };
                let s = f.global(point);
                let mut w = WrenchDerivative::zero();
                w.torque[0] = s.cross(&force);
                w.d[0][1] = df;
                w.d[1][1] = skew(&force) * skew(&s) + skew(&s) * df;
                Some(([Some(*body), None], w))
            }
            ForceData::Torque {
                body,
                torque,
                frame: axes,
            } => {
                // T = τ (global) or A τ' (body axes: ∂T/∂θ = −[T]×).
                let f = frame(Some(*body));
                let c = components(torque, t);
                let mut w = WrenchDerivative::zero();
                match axes {
                    ForceFrame::Global => w.torque[0] = c,
                    ForceFrame::Body => {
                        let g = f.a * c;
                        w.torque[0] = g;
                        w.d[1][1] = -skew(&g);
                    }
                }
                Some(([Some(*body), None], w))
            }
            ForceData::SpringDamper {
                ends,
                stiffness,
                damping,
                actuator,
                free_length,
            } => {
                let (fi, fj) = (frame(ends[0].0), frame(ends[1].0));
                let (si, sj) = (fi.global(&ends[0].1), fj.global(&ends[1].1));
                let d = fj.r + sj - fi.r - si;
                let length = d.norm();
                if length == 0.0 {
                    return None;
                }
                let u = d / length;
                let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
                let rate = u.dot(&d_dot);
                let tension =
                    stiffness * (length - free_length) + damping * rate + actuator.as_ref().map_or(0.0, |f| f.value(t));
                // Columns r_i, θ_i, r_j, θ_j.
                let dd = [-M3::identity(), skew(&si), M3::identity(), -skew(&sj)];
                let dd_dot = [
                    M3::zeros(),
                    skew(&fi.w.cross(&si)),
                    M3::zeros(),
                    -skew(&fj.w.cross(&sj)),
                ];
                // Columns v_i, ω_i, v_j, ω_j.
                let dd_dot_v = [-M3::identity(), skew(&si), M3::identity(), -skew(&sj)];
                let projector = (M3::identity() - u * u.transpose()) / length;
                let arms = [si, sj];
                let force_i = u * tension;
                let forces = [force_i, -force_i];
                let mut w = WrenchDerivative::zero();
                w.torque = [si.cross(&force_i), sj.cross(&-force_i)];
                for c in 0..4 {
                    let du = projector * dd[c];
                    // ∂tension/∂x (a row): k uᵀ ∂d + c (ḋᵀ ∂u + uᵀ ∂ḋ).
                    let dt = (u.transpose() * dd[c]) * *stiffness
                        + (d_dot.transpose() * du + u.transpose() * dd_dot[c]) * *damping;
                    let dfi = u * dt + du * tension;
                    let dt_v = (u.transpose() * dd_dot_v[c]) * *damping;
                    let dfi_v = u * dt_v;
                    for (e, sign) in [(0usize, 1.0), (1, -1.0)] {
                        let df = dfi * sign;
                        // T_e = s_e × F_e: −[F_e]× ∂s_e + [s_e]× ∂F_e, ∂s_e/∂θ_e = −[s_e]×.
                        let ds = if c == 2 * e + 1 { -skew(&arms[e]) } else { M3::zeros() };
                        w.d[2 * e][c] = df;
                        w.d[2 * e + 1][c] = -skew(&forces[e]) * ds + skew(&arms[e]) * df;
                        w.dv[2 * e][c] = dfi_v * sign;
                        w.dv[2 * e + 1][c] = skew(&arms[e]) * dfi_v * sign;
                    }
                }
                Some(([ends[0].0, ends[1].0], w))
            }
            ForceData::AboutAxis(a) => Some(a.wrench_derivative(t, frame)),
            ForceData::AlongAxis(a) => Some(a.wrench_derivative(t, frame)),
            // Not differentiated analytically: the tangent takes central differences.
            ForceData::SpherePlane(_) | ForceData::SweptPair(_) | ForceData::CapsuleGroup(_) | ForceData::User(_) => {
                None
            }
        }
    }
}
