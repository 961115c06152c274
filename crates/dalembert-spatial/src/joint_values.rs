//! Joint-space values of an absolute-coordinate state: the angle of each revolute joint and the
//! displacement of each prismatic joint, with their rates (`docs/scenes.md`, "Joint columns").
//!
//! With the joint frame's axes `x_i, y_i, z_i` on body `i` and `x_j` on body `j` (global), its
//! points `P_i`, `P_j`, and `d = P_j − P_i`:
//!
//! ```text
//! revolute:  θ = atan2(x_j·y_i, x_j·x_i)        θ̇ = z_i·(ω_j − ω_i)
//! prismatic: s = z_i·d                           ṡ = (ω_i × z_i)·d + z_i·(v_Pj − v_Pi)
//! ```
//!
//! and their second derivatives from the accelerations ([`Model::joint_accelerations_into`]).
//!
//! Both are 0 in the initial configuration (the markers coincide there) and positive for a
//! right-handed rotation or a slide of body `j` along `+z_i`: the conventions of URDF and MJCF
//! (child relative to parent about or along the joint axis). `θ` lies in `(−π, π]`; a run's
//! output makes it continuous ([`unwrap_angle`]).
//!
//! [`Model::move_joints`] goes the other way on a tree: it turns (or slides) the side of each
//! given joint away from the ground by the joint's value and adds the joint's rate to that side's
//! velocities, so that the state it makes reads back those values and rates exactly.

use crate::euler_parameters::{from_axis_angle, product};
use crate::frame::{NQ, NV};
use crate::joints::JointKind;
use crate::Model;
use dalembert_system::ModelError;
use nalgebra::Vector3;

/// What a joint value is: an angle (radians) or a displacement (metres).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointValueKind {
    /// A revolute joint's angle.
    Angle,
    /// A prismatic joint's displacement.
    Displacement,
}

/// The angle `candidate` (in `(−π, π]`) moved by a whole number of turns to lie within `π` of
/// `previous` (the seam's, which joint limits use too).
pub use dalembert_system::limit::unwrap_angle;

impl Model {
    /// The joints that have a joint value (revolute and prismatic), with what the value is, in
    /// the model's joint order.
    pub fn joint_value_names(&self) -> impl Iterator<Item = (&str, JointValueKind)> {
        self.joints().iter().filter_map(|j| match j.kind {
            Some(JointKind::Revolute) => Some((j.name.as_str(), JointValueKind::Angle)),
            Some(JointKind::Prismatic) => Some((j.name.as_str(), JointValueKind::Displacement)),
            _ => None,
        })
    }

    /// Writes `(value, rate)` of each joint of [`Model::joint_value_names`] at `(q, v)`, in order,
    /// into `out` (one pair per joint; a shorter `out` takes the first ones). Allocates nothing.
    pub fn joint_values_into(&self, q: &[f64], v: &[f64], out: &mut [(f64, f64)]) {
        let joints = self
            .joints()
            .iter()
            .filter(|j| matches!(j.kind, Some(JointKind::Revolute) | Some(JointKind::Prismatic)));
        for (j, slot) in joints.zip(out.iter_mut()) {
            let fi = self.frame(j.body_i, q, v);
            let fj = self.frame(j.body_j, q, v);
            let axis = |k: usize| -> Vector3<f64> { fi.a * j.axes_i.column(k) };
            let zi = axis(2);
            *slot = if j.kind == Some(JointKind::Revolute) {
                let xj = fj.a * j.axes_j.column(0);
                ((xj.dot(&axis(1))).atan2(xj.dot(&axis(0))), zi.dot(&(fj.w - fi.w)))
            } else {
                let (si, sj) = (fi.a * j.point_i, fj.a * j.point_j);
                let d = fj.r + sj - fi.r - si;
                let rate = fi.w.cross(&zi).dot(&d) + zi.dot(&(fj.point_velocity(&sj) - fi.point_velocity(&si)));
                (zi.dot(&d), rate)
            };
        }
    }

    /// Writes the second derivative of each joint value of [`Model::joint_value_names`] at
    /// `(q, v)` with accelerations `a` (the system's `v̇`: `r̈` global, `ω̇'` body frame), in order,
    /// into `out`. With `α = A ω̇'` the angular acceleration (global), `ż_i = ω_i × z_i`,
    /// `z̈_i = α_i × z_i + ω_i × ż_i`, and a point's acceleration `r̈ + α × s + ω × (ω × s)`:
    ///
    /// ```text
    /// revolute:  θ̈ = ż_i·(ω_j − ω_i) + z_i·(α_j − α_i)
    /// prismatic: s̈ = z̈_i·d + 2 ż_i·ḋ + z_i·d̈
    /// ```
    ///
    /// Allocates nothing.
    pub fn joint_accelerations_into(&self, q: &[f64], v: &[f64], a: &[f64], out: &mut [f64]) {
        let joints = self
            .joints()
            .iter()
            .filter(|j| matches!(j.kind, Some(JointKind::Revolute) | Some(JointKind::Prismatic)));
        let acceleration = |b: Option<usize>, rotation: &nalgebra::Matrix3<f64>| match b {
            None => (Vector3::zeros(), Vector3::zeros()),
            Some(b) => {
                let o = NV * b;
                let omega_dot = Vector3::new(a[o + 3], a[o + 4], a[o + 5]);
                (Vector3::new(a[o], a[o + 1], a[o + 2]), rotation * omega_dot)
            }
        };
        for (j, slot) in joints.zip(out.iter_mut()) {
            let fi = self.frame(j.body_i, q, v);
            let fj = self.frame(j.body_j, q, v);
            let (ai, alpha_i) = acceleration(j.body_i, &fi.a);
            let (aj, alpha_j) = acceleration(j.body_j, &fj.a);
            let zi = fi.a * j.axes_i.column(2);
            let zi_dot = fi.w.cross(&zi);
            *slot = if j.kind == Some(JointKind::Revolute) {
                zi_dot.dot(&(fj.w - fi.w)) + zi.dot(&(alpha_j - alpha_i))
            } else {
                let (si, sj) = (fi.a * j.point_i, fj.a * j.point_j);
                let d = fj.r + sj - fi.r - si;
                let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
                let point = |r: Vector3<f64>, alpha: Vector3<f64>, f: &crate::frame::Frame, s: &Vector3<f64>| {
                    r + alpha.cross(s) + f.centripetal(s)
                };
                let d_ddot = point(aj, alpha_j, &fj, &sj) - point(ai, alpha_i, &fi, &si);
                let zi_ddot = alpha_i.cross(&zi) + fi.w.cross(&zi_dot);
                zi_ddot.dot(&d) + 2.0 * zi_dot.dot(&d_dot) + zi.dot(&d_ddot)
            };
        }
    }
}

/// A joint's value and rate to set ([`Model::move_joints`]).
#[derive(Debug, Clone, PartialEq)]
pub struct JointMove {
    /// The joint's name (a revolute or prismatic joint).
    pub joint: String,
    /// Its angle (rad) or displacement (m) from the model's initial configuration.
    pub value: f64,
    /// Its rate (rad/s or m/s).
    pub rate: f64,
}

impl Model {
    /// Moves the state `(q, v)` by each joint of `moves`: from the model's initial configuration
    /// at rest, each then reads its value and rate ([`Model::joint_values_into`]); from another
    /// state the value is a change (a turn or a slide by it) and the rate is added. The other
    /// joints keep theirs: the bodies on the side of
    /// the joint away from the ground turn about its axis (revolute) or slide along it
    /// (prismatic), and that side's velocities gain the joint's rate. The moves apply in any
    /// order (each carries what lies beyond it rigidly). An error names a joint that is not a
    /// revolute or prismatic joint of the model, or one on a closed loop (its two sides are one:
    /// the loop's other joints would have to move too).
    pub fn move_joints(&self, q: &mut [f64], v: &mut [f64], moves: &[JointMove]) -> Result<(), ModelError> {
        let joints = self.joints();
        let bodies = self.bodies().len();
        let refuse = |name: &str, what: String| ModelError::InvalidParameter {
            element: format!("joint '{name}'"),
            what,
        };
        let mut sides = Vec::with_capacity(moves.len());
        for m in moves {
            let (k, j) = joints
                .iter()
                .enumerate()
                .find(|(_, j)| j.name == m.joint)
                .ok_or_else(|| refuse(&m.joint, "the model has no such joint".into()))?;
            if !matches!(j.kind, Some(JointKind::Revolute) | Some(JointKind::Prismatic)) {
                return Err(refuse(
                    &m.joint,
                    "only a revolute or prismatic joint has a value to set".into(),
                ));
            }
            if !(m.value.is_finite() && m.rate.is_finite()) {
                return Err(refuse(&m.joint, "its value and rate must be finite".into()));
            }
            // The bodies reached from a body without crossing joint k, and whether the ground is.
            let side = |start: Option<usize>| -> (Vec<bool>, bool) {
                let mut seen = vec![false; bodies];
                let Some(first) = start else {
                    return (seen, true);
                };
                seen[first] = true;
                let (mut stack, mut ground) = (vec![first], false);
                while let Some(b) = stack.pop() {
                    for other in joints.iter().enumerate().filter(|(l, _)| *l != k).map(|(_, o)| o) {
                        let next = match (other.body_i, other.body_j) {
                            (Some(x), y) if x == b => y,
                            (x, Some(y)) if y == b => x,
                            _ => continue,
                        };
                        match next {
                            None => ground = true,
                            Some(n) if !seen[n] => {
                                seen[n] = true;
                                stack.push(n);
                            }
                            _ => {}
                        }
                    }
                }
                (seen, ground)
            };
            let ((from_j, j_grounded), (from_i, i_grounded)) = (side(j.body_j), side(j.body_i));
            if j.body_i.is_some_and(|b| from_j[b]) || (j_grounded && i_grounded) {
                return Err(refuse(
                    &m.joint,
                    "it is on a closed loop: setting its value would move the loop's other joints too".into(),
                ));
            }
            // Move the side without the ground: body j's, or body i's the other way.
            let (moving, sign) = if j_grounded { (from_i, -1.0) } else { (from_j, 1.0) };
            sides.push((k, moving, sign, m.value, m.rate));
        }
        for (k, moving, sign, value, _) in &sides {
            let j = &joints[*k];
            let fi = self.frame(j.body_i, q, &[]);
            let (point, axis) = (fi.point(&j.point_i), fi.a * j.axes_i.column(2));
            let turn = from_axis_angle(&axis, sign * value);
            let rotation = crate::euler_parameters::rotation(&turn);
            for b in (0..bodies).filter(|&b| moving[b]) {
                let o = NQ * b;
                let r = Vector3::new(q[o], q[o + 1], q[o + 2]);
                let moved = if j.kind == Some(JointKind::Revolute) {
                    let p = product(&turn, &[q[o + 3], q[o + 4], q[o + 5], q[o + 6]]);
                    q[o + 3..o + 7].copy_from_slice(&p);
                    point + rotation * (r - point)
                } else {
                    r + sign * value * axis
                };
                q[o..o + 3].copy_from_slice(moved.as_slice());
            }
        }
        for (k, moving, sign, _, rate) in &sides {
            let j = &joints[*k];
            let fi = self.frame(j.body_i, q, &[]);
            let (point, axis) = (fi.point(&j.point_i), fi.a * j.axes_i.column(2));
            for b in (0..bodies).filter(|&b| moving[b]) {
                let f = self.frame(Some(b), q, &[]);
                let (dv, dw) = if j.kind == Some(JointKind::Revolute) {
                    (sign * rate * axis.cross(&(f.r - point)), sign * rate * axis)
                } else {
                    (sign * rate * axis, Vector3::zeros())
                };
                let o = NV * b;
                for c in 0..3 {
                    v[o + c] += dv[c];
                }
                let dw_body = f.a.transpose() * dw;
                for c in 0..3 {
                    v[o + 3 + c] += dw_body[c];
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::unwrap_angle;
    use std::f64::consts::PI;

    /// An angle that passes π comes back as π + δ, not −π + δ; one within π of the last is kept.
    #[test]
    fn unwrapping_continues_across_half_turns() {
        assert!((unwrap_angle(3.1, -3.1) - (2.0 * PI - 3.1)).abs() < 1e-15);
        assert!((unwrap_angle(-3.1, 3.1) - (3.1 - 2.0 * PI)).abs() < 1e-15);
        assert_eq!(unwrap_angle(0.5, 0.7), 0.7);
        let far = 7.0 * PI + 0.1;
        assert!((unwrap_angle(far, -PI + 0.2) - (far + 0.1)).abs() < 1e-12);
    }
}
