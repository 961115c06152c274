//! Coulomb friction in a rigid contact of a circle or a flat face with a line, a circle or a cam
//! profile (`docs/limits.md`, "Friction in rigid contact"): the slip row of the contact point,
//! for the seam's stick–slip law ([`dalembert_system::friction`]), loaded by the contact's normal
//! force.
//!
//! The contact's shape is on body 1, the other shape on body 2, and `n` is the unit normal out of
//! the other shape towards the contact's (`s = perp(n)`, turning at `φ̇`: `ṅ = φ̇ s`,
//! `ṡ = −φ̇ n`). `P₁`, `P₂` are the contact points on each body. The slip rate is the relative
//! velocity of the two bodies' material points there along the tangent `τ = −s = (n_y, −n_x)`
//! (on a floor whose normal is `+y`, `τ = +x`), and its time derivative, with `T_i` the rate of
//! `n·(P_i − r_i)` at fixed body velocities:
//!
//! ```text
//! w = τ·(v₁(P₁) − v₂(P₂)) = −(s·(ṙ₁ − ṙ₂) + ω₁ n·(P₁ − r₁) − ω₂ n·(P₂ − r₂))              (L7)
//! ẇ = g·q̈ + b,   −b = −φ̇ n·(ṙ₁ − ṙ₂) + ω₁ T₁ − ω₂ T₂
//! ```
//!
//! | against | `n`, `φ̇` | `P₁`, `T₁` | `P₂`, `T₂` |
//! |---|---|---|---|
//! | a line of body 2 | the line's, `ω₂` | `c₁ − R₁ n`, `(φ̇ − ω₁) s·a₁` | `c₁ − R₁ n`, `ω₂ s·(c₁ − r₂) + n·(ċ₁ − ṙ₂)` |
//! | a circle `c₂ = r₂ + a₂` | `(c₁ − c₂)/d`, `s·(ċ₁ − ċ₂)/d` | `c₁ − R₁ n`, `(φ̇ − ω₁) s·a₁` | `c₂ + R₂ n`, `(φ̇ − ω₂) s·a₂` |
//! | a profile, closest point `x(u*) = r₂ + b` | `(c₁ − x)/d`, `s·(ċ₁ − ẋ − x_u u̇*)/d` | `c₁ − R₁ n`, `(φ̇ − ω₁) s·a₁` | `x`, `(φ̇ − ω₂) s·b` |
//! | a face on body 1 (normal `n_f`) on a profile, support point `x` | `−n_f`, `ω₁` | `x`, `ω₁ s·(x − r₁) + n·(ẋ − ṙ₁)` | `x`, `(ω₁ − ω₂) s·b` |
//!
//! with `c₁ = r₁ + a₁` the circle's centre, `d` the distance of the centres (or of the centre
//! from the profile's point), `ẋ = ṙ₂ + ω₂ perp(b)` the profile's material point's velocity,
//! `x_u` its tangent and `u̇* = ((ċ₁ − ẋ)·x_u + ω₂ (c₁ − x)·perp(x_u)) / (|x_u|² − (c₁ − x)·x_uu)`
//! the closest point's motion along it (the closest point, `x_u ⟂ n`, and the support point do not
//! move `n·P₂` by moving along the profile). The friction force `F` acts on body 1 along `τ` at
//! `P₁` and on body 2 opposite at `P₂`; its power is `F w`.

use crate::rigid_contact::{Against, RigidContact};
use dalembert_kinematics::rotation::{cross, perp};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};
use dalembert_system::SlipRow;

/// One contact's geometry for (L7): `n`, `φ̇`, the contact points `P₁`, `P₂` and the rates `T₁`,
/// `T₂`.
struct Touch {
    n: Vec2,
    phi_dot: f64,
    points: [Vec2; 2],
    rates: [f64; 2],
}

impl RigidContact {
    /// The slip row of the contact point at `(q, v)` ((L7) above): `w = g·v` and the bias of
    /// `ẇ = g·q̈ + b`. Empty for concentric circles, or a circle on the profile's curve itself.
    pub fn slip_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) {
        out.clear();
        let one = BodyState::of(self.body, q, v);
        let two = BodyState::of(self.other_body(), q, v);
        let Some(touch) = self.touch(&one, &two) else {
            return;
        };
        let (n, phi_dot) = (touch.n, touch.phi_dot);
        let s = perp(n);
        let tau = -s;
        for (body, state, point, sign) in [
            (self.body, &one, touch.points[0], 1.0),
            (self.other_body(), &two, touch.points[1], -1.0),
        ] {
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
        // `−b` of (L7): the bias of the rate along `s` (`w` with its sign turned).
        let relative = one.velocity - two.velocity;
        let along_s = -phi_dot * n.dot(&relative) + one.omega * touch.rates[0] - two.omega * touch.rates[1];
        out.bias = -along_s;
    }

    /// The geometry of (L7) for the contact's shape on `one` and the other shape on `two`.
    fn touch(&self, one: &BodyState, two: &BodyState) -> Option<Touch> {
        let a1 = one.rotation() * self.centre;
        let c1 = one.position + a1;
        let c1_dot = one.velocity + perp(a1) * one.omega;
        let circle = |n: Vec2, phi_dot: f64, p2: Vec2, t2: f64| Touch {
            n,
            phi_dot,
            points: [c1 - n * self.radius, p2],
            rates: [(phi_dot - one.omega) * perp(n).dot(&a1), t2],
        };
        match &self.against {
            &Against::Line { normal, .. } => {
                let n = two.rotation() * normal;
                let t2 = two.omega * perp(n).dot(&(c1 - two.position)) + n.dot(&(c1_dot - two.velocity));
                Some(circle(n, two.omega, c1 - n * self.radius, t2))
            }
            &Against::Circle { centre, radius, .. } => {
                let a2 = two.rotation() * centre;
                let d = c1 - (two.position + a2);
                let length = d.norm();
                if length.is_nan() || length == 0.0 {
                    return None;
                }
                let n = d / length;
                let c2_dot = two.velocity + perp(a2) * two.omega;
                let phi_dot = perp(n).dot(&(c1_dot - c2_dot)) / length;
                let t2 = (phi_dot - two.omega) * perp(n).dot(&a2);
                Some(circle(n, phi_dot, two.position + a2 + n * radius, t2))
            }
            Against::Profile { profile, .. } => {
                let local = two.rotation().transpose() * (c1 - two.position);
                let [point, tangent, bend] = profile.at(profile.closest(local));
                let x = PointState::new(two, point);
                let (x_u, x_uu) = (two.rotation() * tangent, two.rotation() * bend);
                let gap = c1 - x.position;
                let length = gap.norm();
                let slide = x_u.norm_squared() - gap.dot(&x_uu);
                if length.is_nan() || length == 0.0 || slide <= 0.0 {
                    return None;
                }
                let n = gap / length;
                let u_dot = ((c1_dot - x.velocity).dot(&x_u) + two.omega * gap.dot(&perp(x_u))) / slide;
                let phi_dot = perp(n).dot(&(c1_dot - x.velocity - x_u * u_dot)) / length;
                let t2 = (phi_dot - two.omega) * perp(n).dot(&x.arm);
                Some(circle(n, phi_dot, x.position, t2))
            }
            Against::ProfileFace { profile, normal, .. } => {
                let face = one.rotation() * normal;
                let local = two.rotation().transpose() * face;
                let [point, _, _] = profile.at(profile.support(local));
                let x = PointState::new(two, point);
                let n = -face;
                let s = perp(n);
                let t1 = one.omega * s.dot(&(x.position - one.position)) + n.dot(&(x.velocity - one.velocity));
                let t2 = (one.omega - two.omega) * s.dot(&x.arm);
                Some(Touch {
                    n,
                    phi_dot: one.omega,
                    points: [x.position, x.position],
                    rates: [t1, t2],
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Profile;
    use crate::rigid_contact::tests::egg;
    use dalembert_kinematics::BodyId;

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
    /// contact points on each body (the circle's `c₁ − R₁ n`; the line's point under it, the other
    /// circle's `c₂ + R₂ n`, the profile's closest or support point), along `τ = (n_y, −n_x)`.
    fn slip_rate(c: &RigidContact, q: &[f64], v: &[f64]) -> f64 {
        let one = BodyState::of(c.body, q, v);
        let two = BodyState::of(c.other_body(), q, v);
        let c1 = PointState::new(&one, c.centre).position;
        let (n, p1, p2) = match &c.against {
            Against::Line { normal, .. } => {
                let n = two.rotation() * normal;
                (n, c1 - n * c.radius, c1 - n * c.radius)
            }
            Against::Circle { centre, radius, .. } => {
                let c2 = PointState::new(&two, *centre).position;
                let n = (c1 - c2).normalize();
                (n, c1 - n * c.radius, c2 + n * *radius)
            }
            Against::Profile { profile, .. } => {
                let u = profile.closest(two.rotation().transpose() * (c1 - two.position));
                let x = two.position + two.rotation() * profile.at(u)[0];
                let n = (c1 - x).normalize();
                (n, c1 - n * c.radius, x)
            }
            Against::ProfileFace { profile, normal, .. } => {
                let face = one.rotation() * normal;
                let u = profile.support(two.rotation().transpose() * face);
                let x = two.position + two.rotation() * profile.at(u)[0];
                (-face, x, x)
            }
        };
        let at = |s: &BodyState, p: Vec2| s.velocity + perp(p - s.position) * s.omega;
        Vec2::new(n.y, -n.x).dot(&(at(&one, p1) - at(&two, p2)))
    }

    /// Along q(t) = q + v t + a t²/2, v(t) = v + a t: the row's `g·v` must be the slip rate
    /// from the material points, and `g·a + b` its time derivative by central differences at
    /// 2e-4 s and 1e-4 s extrapolated (truncation O(h⁴) on a line or a circle; on a profile, whose
    /// third derivative jumps at its knots, O(h²) where the contact point crosses one; round-off
    /// 1e-12; the bar 1e-9 relative; a plain difference at 1e-4 s is off by up to 5e-7).
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
        // Central differences at h and h/2, extrapolated (Richardson): truncation O(h⁴).
        let central = |h: f64| {
            let (qp, vp) = at(h);
            let (qm, vm) = at(-h);
            (slip_rate(c, &qp, &vp) - slip_rate(c, &qm, &vm)) / (2.0 * h)
        };
        let h = 2e-4;
        let fd = (4.0 * central(h / 2.0) - central(h)) / 3.0;
        let acceleration = row.dot(&a) + row.bias;
        assert!(
            (acceleration - fd).abs() < 1e-9 * (1.0 + fd.abs()),
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

    #[test]
    fn the_slip_row_on_a_cam_profile_is_the_material_points_relative_velocity() {
        // A roller (radius 0.02) near the egg (body 0) and a flat face (normal (0.3, −1)/|…|
        // towards it) on it, at five cam angles: the closest and the support point move along
        // the profile as the bodies move.
        for angle in [0.3f64, 1.7, 2.9, 4.4, 5.8] {
            let mut roller = contact(Against::Profile {
                body: BodyRef::Body(BodyId(0)),
                profile: Profile::closed_spline(&egg()).unwrap(),
            });
            roller.radius = 0.02;
            roller.centre = Vec2::new(0.01, -0.02);
            let near = 0.02 + 0.12 * (angle + 0.2).sin();
            let q = [0.002, -0.001, angle, 0.01 + 0.12 * (angle + 0.2).cos(), near, 0.4];
            assert_row(&roller, q, &format!("roller at {angle}"));
            let face = contact(Against::ProfileFace {
                body: BodyRef::Body(BodyId(0)),
                profile: Profile::closed_spline(&egg()).unwrap(),
                normal: Vec2::new(0.3, -1.0).normalize(),
            });
            assert_row(
                &face,
                [0.002, -0.001, angle, 0.03, 0.15, 0.2],
                &format!("face at {angle}"),
            );
        }
    }
}
