//! Couplings between joint values (`docs/couplings.md`): a URDF `mimic` (the follower's value a
//! multiple of the leader's plus an offset) or an MJCF `equality joint` (a polynomial of it), as
//! one exact constraint equation over the bodies of both joints:
//!
//! ```text
//! C = w_f − p(w_l),   p(x) = c₀ + c₁ x + c₂ x² + …
//! C_q = g_f − p′(w_l) g_l
//! Q_d = −(C̈ at zero accelerations) = −b_f + p′(w_l) b_l + p″(w_l) ẇ_l²
//! ```
//!
//! `w` is a joint's value (an angle or a displacement, 0 in the model's initial configuration),
//! `g` its row and `b` its bias (`crate::limits`, whose formulas `joint_value_row` gives once
//! for both). Without a leader, `C = w_f − c₀` holds the follower at a value. A revolute
//! follower's `C` is taken within a turn (`θ_f − p` wrapped to `(−π, π]`), so the follower may
//! turn any number of times; a revolute leader's angle is read within a turn of the initial
//! configuration, so a coupling whose polynomial is not `θ ↦ c₀ ± θ` holds while the leader stays
//! within half a turn of it.
//!
//! The multiplier `λ` is the coupling's effort: `−λ` is the torque (or force) it applies along
//! the follower joint, on the follower's second body.

use crate::frame::Frame;
use crate::joints::primitives::Row;
use crate::joints::{JointData, JointKind};
use dalembert_system::ModelError;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// A coupling of one joint's value to another's, `w_follower = p(w_leader)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Coupling {
    /// Name (messages and output).
    pub name: String,
    /// The revolute or prismatic joint whose value the follower's follows (`None`: the follower
    /// is held at `polynomial[0]`).
    pub leader: Option<String>,
    /// The revolute or prismatic joint that follows.
    pub follower: String,
    /// `p`'s coefficients `c₀, c₁, …` (rad or m as the joints' values are).
    pub polynomial: Vec<f64>,
}

impl Coupling {
    /// `w_follower = multiplier · w_leader + offset` (URDF's `mimic`).
    pub fn linear(name: &str, leader: &str, follower: &str, multiplier: f64, offset: f64) -> Self {
        Coupling {
            name: name.to_string(),
            leader: Some(leader.to_string()),
            follower: follower.to_string(),
            polynomial: vec![offset, multiplier],
        }
    }

    /// `p(x)`, `p′(x)` and `p″(x)` (Horner's rule).
    pub fn polynomial_at(&self, x: f64) -> [f64; 3] {
        polynomial_at(&self.polynomial, x)
    }
}

/// `p(x)`, `p′(x)` and `p″(x)` of the coefficients `c₀, c₁, …` by Horner's rule.
fn polynomial_at(coefficients: &[f64], x: f64) -> [f64; 3] {
    let (mut p, mut d1, mut d2) = (0.0, 0.0, 0.0);
    for &c in coefficients.iter().rev() {
        d2 = d2 * x + 2.0 * d1;
        d1 = d1 * x + p;
        p = p * x + c;
    }
    [p, d1, d2]
}

/// A coupling in model terms: its joints' indices and the distinct bodies its row spans.
#[derive(Debug, Clone)]
pub(crate) struct CouplingData {
    pub name: String,
    pub leader: Option<usize>,
    pub follower: usize,
    pub polynomial: Vec<f64>,
    /// The moving bodies of both joints, each once, in storage order of the row's entries.
    pub bodies: Vec<usize>,
    /// The follower is revolute: `C` is taken within a turn.
    pub wrap: bool,
}

impl CouplingData {
    /// Checks `c` against the model's joints (errors name the coupling).
    pub fn new(c: &Coupling, joints: &[JointData]) -> Result<Self, ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("coupling '{}'", c.name),
            what,
        };
        if c.polynomial.is_empty() || c.polynomial.iter().any(|x| !x.is_finite()) {
            return Err(bad("its polynomial needs at least one coefficient, all finite".into()));
        }
        if c.leader.is_some() && c.polynomial.len() < 2 {
            return Err(bad(
                "a coupling to a leader needs a multiplier (c₁) after the offset".into()
            ));
        }
        let find = |name: &str| -> Result<usize, ModelError> {
            let k = joints
                .iter()
                .position(|j| j.name == name)
                .ok_or_else(|| bad(format!("no joint named '{name}'")))?;
            match joints[k].kind {
                Some(JointKind::Revolute | JointKind::Prismatic) => Ok(k),
                Some(other) => Err(bad(format!(
                    "joint '{name}' is {}: a coupling joins revolute and prismatic joints",
                    other.name()
                ))),
                None => Err(bad(format!("'{name}' is a driver, not a joint"))),
            }
        };
        let follower = find(&c.follower)?;
        let leader = c.leader.as_deref().map(find).transpose()?;
        if leader == Some(follower) {
            return Err(bad(format!("joint '{}' cannot follow itself", c.follower)));
        }
        let mut bodies = Vec::with_capacity(4);
        for j in leader.iter().chain([&follower]) {
            for b in [joints[*j].body_i, joints[*j].body_j].into_iter().flatten() {
                if !bodies.contains(&b) {
                    bodies.push(b);
                }
            }
        }
        Ok(CouplingData {
            name: c.name.clone(),
            leader,
            follower,
            polynomial: c.polynomial.clone(),
            bodies,
            wrap: joints[follower].kind == Some(JointKind::Revolute),
        })
    }

    /// The coupling's equation at the frames `frame` gives: `C`, `Q_d`, and its Jacobian as
    /// global `[ṙ; ω]` parts on up to four joint ends (`None` for the ground or an unused end).
    pub fn row(&self, joints: &[JointData], frame: &dyn Fn(Option<usize>) -> Frame) -> (f64, f64, [End; 4]) {
        let f = &joints[self.follower];
        let (rf, _) = joint_value_row(f, &frame(f.body_i), &frame(f.body_j));
        let mut ends = [(None, [V3::zeros(); 2]); 4];
        ends[0] = (f.body_i, rf.i);
        ends[1] = (f.body_j, rf.j);
        let (mut c, mut gamma) = (rf.c, rf.gamma);
        match self.leader {
            None => c -= self.polynomial[0],
            Some(l) => {
                let l = &joints[l];
                let (rl, rate) = joint_value_row(l, &frame(l.body_i), &frame(l.body_j));
                let [p, d1, d2] = polynomial_at(&self.polynomial, rl.c);
                c -= p;
                gamma += -d1 * rl.gamma + d2 * rate * rate;
                ends[2] = (l.body_i, rl.i.map(|g| -d1 * g));
                ends[3] = (l.body_j, rl.j.map(|g| -d1 * g));
            }
        }
        if self.wrap {
            c = wrap_angle(c);
        }
        (c, gamma, ends)
    }
}

/// A joint end of a coupling's row: its body and its global `[ṙ; ω]` part.
pub(crate) type End = (Option<usize>, [V3; 2]);

/// `x` moved by whole turns into `(−π, π]`.
pub(crate) fn wrap_angle(x: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let y = x - tau * (x / tau).round();
    if y <= -std::f64::consts::PI {
        y + tau
    } else {
        y
    }
}

/// A revolute or prismatic joint's value as a constraint row (`crate::limits`' formulas): `c`
/// the value, the global `[ṙ; ω]` parts of its rate on ends `i` and `j`, and `gamma` the
/// negated bias (`−ẅ` at zero accelerations); with the value's rate.
pub(crate) fn joint_value_row(j: &JointData, fi: &Frame, fj: &Frame) -> (Row, f64) {
    let axis = |k: usize| -> V3 { fi.a * j.axes_i.column(k) };
    let zi = axis(2);
    let zi_dot = fi.w.cross(&zi);
    if j.kind == Some(JointKind::Revolute) {
        let xj = fj.a * j.axes_j.column(0);
        let row = Row {
            c: xj.dot(&axis(1)).atan2(xj.dot(&axis(0))),
            c_t: 0.0,
            i: [V3::zeros(), -zi],
            j: [V3::zeros(), zi],
            gamma: -zi_dot.dot(&(fj.w - fi.w)),
        };
        (row, zi.dot(&(fj.w - fi.w)))
    } else {
        let (si, sj) = (fi.a * j.point_i, fj.a * j.point_j);
        let d = fj.r + sj - fi.r - si;
        let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
        let centripetal = fj.centripetal(&sj) - fi.centripetal(&si);
        let row = Row {
            c: zi.dot(&d),
            c_t: 0.0,
            i: [-zi, zi.cross(&(d + si))],
            j: [zi, sj.cross(&zi)],
            gamma: -(fi.w.cross(&zi_dot).dot(&d) + 2.0 * zi_dot.dot(&d_dot) + zi.dot(&centripetal)),
        };
        (row, zi_dot.dot(&d) + zi.dot(&d_dot))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horner_gives_the_polynomial_and_its_two_derivatives() {
        // p = 1 + 2x − 3x² + 0.5x³ at x = 1.5, differentiated by hand.
        let x: f64 = 1.5;
        let [p, d1, d2] = polynomial_at(&[1.0, 2.0, -3.0, 0.5], x);
        assert!((p - (1.0 + 2.0 * x - 3.0 * x * x + 0.5 * x.powi(3))).abs() < 1e-14);
        assert!((d1 - (2.0 - 6.0 * x + 1.5 * x * x)).abs() < 1e-14);
        assert!((d2 - (-6.0 + 3.0 * x)).abs() < 1e-14);
    }

    #[test]
    fn wrapping_keeps_the_angle_within_a_half_turn() {
        use std::f64::consts::{PI, TAU};
        for x in [0.3, -0.3, PI, 3.0 * PI, -PI, 2.9, -2.9] {
            let y = wrap_angle(x + 2.0 * TAU);
            assert!(y > -PI && y <= PI + 1e-15, "{x} -> {y}");
            assert!(((y - x) / TAU - ((y - x) / TAU).round()).abs() < 1e-12);
        }
    }
}
