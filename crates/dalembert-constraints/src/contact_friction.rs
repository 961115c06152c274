//! Coulomb friction in a rigid circle–line or circle–circle contact (`docs/limits.md`, "Friction
//! in rigid contact"): the slip row of the contact point, for the seam's stick–slip law
//! ([`dalembert_system::friction`]), loaded by the contact's normal force.
//!
//! The circle (centre `c₁ = r₁ + a₁` on body 1, radius `R₁`) touches the other shape along the
//! unit normal `n` (out of the other shape, towards the circle): a line's normal, fixed in its
//! body 2 and turning with it (`φ̇ = ω₂`), or `n = (c₁ − c₂) / |c₁ − c₂|` between two circles
//! (`φ̇ = s·(ċ₁ − ċ₂) / |c₁ − c₂|`, `s = perp(n)`). The contact points are the circle's
//! `P₁ = c₁ − R₁ n` and the other shape's `P₂` (the line's point under the circle,
//! `c₁ − R₁ n`; the other circle's `c₂ + R₂ n`). The slip rate is the relative velocity of the
//! two bodies' material points there along the tangent `τ = −perp(n) = (n_y, −n_x)` (on a
//! floor whose normal is `+y`, `τ = +x`):
//!
//! ```text
//! w = τ·(v₁(P₁) − v₂(P₂)) = −(s·(ṙ₁ − ṙ₂) + ω₁ n·(P₁ − r₁) − ω₂ n·(P₂ − r₂))            (L7)
//! ẇ = g·q̈ + b,   −b = −φ̇ n·(ṙ₁ − ṙ₂) + ω₁ (φ̇ s·a₁ − ω₁ s·a₁) − ω₂ X
//! line:   X = ω₂ s·(c₁ − r₂) + n·(ċ₁ − ṙ₂)
//! circle: X = φ̇ s·a₂ − ω₂ s·a₂
//! ```
//!
//! (with `ṅ = φ̇ s`, `ṡ = −φ̇ n`, `ȧ = ω perp(a)` and `n·perp(a) = −s·a`). The friction force `F`
//! acts on the circle along `τ` at `P₁` and on the other body opposite at `P₂`; its power is
//! `F w`.

use crate::rigid_contact::{Against, RigidContact};
use dalembert_kinematics::rotation::{cross, perp};
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::SlipRow;

impl RigidContact {
    /// The slip row of the contact point at `(q, v)` ((L7) above): `w = g·v` and the bias of
    /// `ẇ = g·q̈ + b`. Empty for a cam profile (its friction is refused) or concentric circles.
    pub fn slip_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) {
        out.clear();
        let one = BodyState::of(self.body, q, v);
        let a1 = one.rotation() * self.centre;
        let c1 = one.position + a1;
        let c1_dot = one.velocity + perp(a1) * one.omega;
        let (two_body, two, n, phi_dot, p2, x) = match self.against {
            Against::Line { body, normal, .. } => {
                let two = BodyState::of(body, q, v);
                let n = two.rotation() * normal;
                let s = perp(n);
                let p2 = c1 - n * self.radius;
                let x = two.omega * s.dot(&(c1 - two.position)) + n.dot(&(c1_dot - two.velocity));
                (body, two, n, two.omega, p2, x)
            }
            Against::Circle { body, centre, radius } => {
                let two = BodyState::of(body, q, v);
                let a2 = two.rotation() * centre;
                let d = c1 - (two.position + a2);
                let length = d.norm();
                if !(length > 0.0) {
                    return;
                }
                let n = d / length;
                let s = perp(n);
                let c2_dot = two.velocity + perp(a2) * two.omega;
                let phi_dot = s.dot(&(c1_dot - c2_dot)) / length;
                let p2 = two.position + a2 + n * radius;
                let x = phi_dot * s.dot(&a2) - two.omega * s.dot(&a2);
                (body, two, n, phi_dot, p2, x)
            }
            Against::Profile { .. } | Against::ProfileFace { .. } => return,
        };
        let s = perp(n);
        let tau = -s;
        let p1 = c1 - n * self.radius;
        for (body, state, point, sign) in [(self.body, &one, p1, 1.0), (two_body, &two, p2, -1.0)] {
            if let BodyRef::Body(id) = body {
                let f = tau * sign;
                let arm: Vec2 = point - state.position;
                for (k, g) in [f.x, f.y, cross(arm, f)].into_iter().enumerate() {
                    if g != 0.0 {
                        out.push(id.offset() + k, g);
                    }
                }
            }
        }
        let relative = one.velocity - two.velocity;
        // `−b` of (L7): the bias of the rate along `s` (`w` with its sign turned).
        let along_s = -phi_dot * n.dot(&relative) + one.omega * (phi_dot - one.omega) * s.dot(&a1) - two.omega * x;
        out.bias = -along_s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dalembert_kinematics::BodyId;
    use dalembert_kinematics::PointState;

    /// A contact of a circle on body 1 (radius 0.2, centre off the body's reference point)
    /// against `against`.
    fn contact(against: Against) -> RigidContact {
        RigidContact {
            name: "wheel".into(),
            body: BodyRef::Body(BodyId(1)),
            centre: Vec2::new(0.05, -0.03),
            radius: 0.2,
            against,
            restitution: 0.0,
            rest_speed: 1e-3,
            friction: Some(0.3),
        }
    }

    /// The slip rate computed from the bodies' material points (independently of the row): the
    /// circle's point `c₁ − R₁ n` and the other body's point under it, along `τ = (n_y, −n_x)`.
    fn slip_rate(c: &RigidContact, q: &[f64], v: &[f64]) -> f64 {
        let one = BodyState::of(c.body, q, v);
        let c1 = PointState::new(&one, c.centre).position;
        let (two, n, p2) = match c.against {
            Against::Line { body, normal, .. } => {
                let two = BodyState::of(body, q, v);
                let n = two.rotation() * normal;
                (two, n, c1 - n * c.radius)
            }
            Against::Circle { body, centre, radius } => {
                let two = BodyState::of(body, q, v);
                let c2 = PointState::new(&two, centre).position;
                let n = (c1 - c2).normalize();
                (two, n, c2 + n * radius)
            }
            _ => unreachable!(),
        };
        let p1 = c1 - n * c.radius;
        let at = |s: &BodyState, p: Vec2| s.velocity + perp(p - s.position) * s.omega;
        Vec2::new(n.y, -n.x).dot(&(at(&one, p1) - at(&two, p2)))
    }

    /// Along q(t) = q + v t + a t²/2, v(t) = v + a t: the row's `g·v` must be the slip rate
    /// from the material points, and `g·a + b` its central difference in time (step 1e-4 s:
    /// truncation ~1e-8 of the scale, round-off 1e-12/h).
    fn assert_row(c: &RigidContact, q: [f64; 6], what: &str) {
        let v = [0.4, -0.3, 5.0, -0.2, 0.6, -3.0];
        let a = [1.0, 2.0, -30.0, -4.0, 3.0, 15.0];
        let at = |t: f64| -> (Vec<f64>, Vec<f64>) {
            (
                (0..6).map(|i| q[i] + v[i] * t + 0.5 * a[i] * t * t).collect(),
                (0..6).map(|i| v[i] + a[i] * t).collect(),
            )
        };
        let mut row = SlipRow::default();
        c.slip_row(&q, &v, &mut row);
        let rate = slip_rate(c, &q, &v);
        assert!(
            (row.dot(&v) - rate).abs() < 1e-13 * (1.0 + rate.abs()),
            "{what}: {} vs {rate}",
            row.dot(&v)
        );
        let h = 1e-4;
        let (qp, vp) = at(h);
        let (qm, vm) = at(-h);
        let fd = (slip_rate(c, &qp, &vp) - slip_rate(c, &qm, &vm)) / (2.0 * h);
        let acceleration = row.dot(&a) + row.bias;
        assert!(
            (acceleration - fd).abs() < 1e-6 * (1.0 + fd.abs()),
            "{what}: slip acceleration {acceleration} vs {fd}"
        );
    }

    #[test]
    fn the_slip_row_against_a_turning_line_is_the_material_points_relative_velocity() {
        let c = contact(Against::Line {
            body: BodyRef::Body(BodyId(0)),
            point: Vec2::new(0.1, 0.0),
            normal: Vec2::new(0.6, 0.8),
        });
        for angle in [0.0f64, 0.7, 2.5, -1.9] {
            assert_row(
                &c,
                [0.1, -0.2, angle, 0.4, 0.9, 0.3 - angle],
                &format!("line at {angle}"),
            );
        }
        // The ground's line.
        let c = contact(Against::Line {
            body: BodyRef::Ground,
            point: Vec2::zeros(),
            normal: Vec2::new(0.0, 1.0),
        });
        assert_row(&c, [0.0, 0.0, 0.0, 0.4, 0.25, 1.1], "floor");
    }

    #[test]
    fn the_slip_row_between_two_circles_is_the_material_points_relative_velocity() {
        let c = contact(Against::Circle {
            body: BodyRef::Body(BodyId(0)),
            centre: Vec2::new(-0.1, 0.07),
            radius: 0.3,
        });
        for angle in [0.0f64, 0.7, 2.5, -1.9] {
            assert_row(
                &c,
                [0.1, -0.2, angle, 0.5, 0.3, 1.0 - angle],
                &format!("circles at {angle}"),
            );
        }
    }
}
