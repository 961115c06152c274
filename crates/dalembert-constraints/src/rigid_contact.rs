//! Rigid (unilateral) contact of a circle on a planar body with a line on another body or the
//! ground, or with another circle (`docs/limits.md`, "Rigid contact"): a gap `s ≥ 0` kept by the
//! same impact and resting law as a joint limit ([`dalembert_system::limit`]), with Coulomb
//! friction if asked (its slip row: [`crate::contact_friction`]).
//!
//! - Against a line with point `p` and unit normal `n` fixed in its body: `s = n·(c − p) − R`,
//!   where `s + R` is the coordinate of the centre `c` along `n` from `p`, the
//!   [`line_coordinate`] primitive (its row gives `w = ṡ` and the bias of `s̈`).
//! - Against another circle: `s = |c₂ − c₁| − R₁ − R₂`, the [`distance`] primitive.
//! - Against a closed profile `x(u)` on another body (a roller on a cam, [`Profile`]):
//!   `s = min_u |c − x(u)| − R`. At the closest point `u*` the row is the [`distance`]
//!   primitive's between the profile's material point there and the centre (the envelope
//!   theorem: `u*` moving does not change `ṡ`), and `s̈` gains the closest point's motion along
//!   the profile: with `d(u) = |c − x(u)|`,
//!
//! ```text
//! s̈ = d_q q̈ + d_qq[q̇, q̇] − (d_uq q̇)² / d_uu
//! d_uq q̇ = −((ċ − ẋ)·x_u + (c − x)·ẋ_u) / d,   ẋ_u = θ̇ perp(x_u)
//! d_uu = (|x_u|² − (n·x_u)²) / d − n·x_uu,      n = (c − x) / d
//! ```
//!
//! - A flat face (the line through a point `p` with unit normal `n` on the contact's body,
//!   towards the profile) against a closed convex profile (a flat-faced follower on a cam):
//!   `s = min_u n·(x(u) − p)`, the profile's support point; the row is the [`line_coordinate`]
//!   primitive's of the profile's material point there, and with `f(u) = n·(x(u) − p)`,
//!
//! ```text
//! s̈ = f_q q̈ + f_qq[q̇, q̇] − (f_uq q̇)² / f_uu,   f_uq q̇ = ṅ·x_u + n·ẋ_u,   f_uu = n·x_uu
//! ```
//!
//! The normal passes through the centres (for a profile, through the roller's centre and the
//! profile's normal), so the impulse along it turns no circle about its centre.

use crate::primitives::{distance, line_coordinate};
use crate::profile::Profile;
use dalembert_kinematics::rotation::perp;
use dalembert_kinematics::PointState;
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::{JointLimit, ModelError, SlipRow};

/// A circle on a body in rigid contact with a line on another body or the ground.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidContact {
    /// The contact's name.
    pub name: String,
    /// The body carrying the circle.
    pub body: BodyRef,
    /// The circle's centre, local to the body.
    pub centre: Vec2,
    /// The circle's radius (m).
    pub radius: f64,
    /// What the circle touches.
    pub against: Against,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which the circle rests on the line (m/s).
    pub rest_speed: f64,
    /// Coulomb's coefficient `μ ≥ 0` of friction at the contact point (`docs/limits.md`,
    /// "Friction in rigid contact"), or `None` for a frictionless contact.
    pub friction: Option<f64>,
}

/// What a rigid contact's circle touches.
#[derive(Debug, Clone, PartialEq)]
pub enum Against {
    /// A line fixed in a body or the ground.
    Line {
        /// The body carrying the line (the ground: global point and normal).
        body: BodyRef,
        /// A point of the line, local to its body.
        point: Vec2,
        /// The line's unit normal, towards the circle's side, local to its body.
        normal: Vec2,
    },
    /// Another circle.
    Circle {
        /// The body carrying it.
        body: BodyRef,
        /// Its centre, local to its body.
        centre: Vec2,
        /// Its radius (m).
        radius: f64,
    },
    /// A closed profile (a cam's), the circle outside it (a roller follower).
    Profile {
        /// The body carrying the profile.
        body: BodyRef,
        /// The profile, local to its body.
        profile: Profile,
    },
    /// A closed convex profile (a cam's) against a flat face of the contact's body (a
    /// flat-faced follower): the line through the contact's `centre` with unit `normal` (local
    /// to the contact's body, towards the profile); the contact's radius is not used.
    ProfileFace {
        /// The body carrying the profile.
        body: BodyRef,
        /// The profile, local to its body.
        profile: Profile,
        /// The face's unit normal, local to the contact's body, towards the profile.
        normal: Vec2,
    },
}

impl RigidContact {
    /// The body the circle touches (a line's or the other circle's).
    pub(crate) fn other_body(&self) -> BodyRef {
        match self.against {
            Against::Line { body, .. }
            | Against::Circle { body, .. }
            | Against::Profile { body, .. }
            | Against::ProfileFace { body, .. } => body,
        }
    }

    /// What the seam sees: a limit on the gap with the single bound `0 ≤ s`.
    pub fn spec(&self) -> JointLimit {
        JointLimit::contact(&self.name, self.restitution, self.rest_speed)
    }

    /// Checks the geometry and coefficients, naming the contact; the shapes must start apart or
    /// touching (a gap of at least −1e-12 m).
    pub fn validate(&self, q0: &[f64]) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        };
        check_shapes(&self.name, self.body, self.radius, &self.against)?;
        self.spec().check().map_err(bad)?;
        if let Some(mu) = self.friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(bad(format!("friction coefficient must be ≥ 0, got {mu}")));
            }
        }
        let gap = self.gap(q0);
        if gap < -1e-12 {
            let what = match self.against {
                Against::Line { .. } => "the circle starts {} m into the line",
                Against::Circle { .. } => "the circles start {} m into each other",
                Against::Profile { .. } => "the circle starts {} m into the profile",
                Against::ProfileFace { .. } => "the face starts {} m into the profile",
            };
            return Err(bad(what.replace("{}", &format!("{:e}", -gap))));
        }
        Ok(())
    }

    /// The gap at `q`.
    pub fn gap(&self, q: &[f64]) -> f64 {
        self.gap_row(q, &[], &mut SlipRow::default())
    }

    /// The gap's row at `(q, v)` for the seam (`v` empty: at rest), and the gap.
    pub fn gap_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        let circle = BodyState::of(self.body, q, v);
        let other = BodyState::of(self.other_body(), q, v);
        let mut envelope = 0.0;
        let (row, reach) = match &self.against {
            Against::Profile { profile, .. } => {
                // The closest point, found in the profile's body frame.
                let c = PointState::new(&circle, self.centre);
                let local = other.rotation().transpose() * (c.position - other.position);
                let [point, tangent, bend] = profile.at(profile.closest(local));
                let Some(row) = distance(&other, point, &circle, self.centre) else {
                    out.clear();
                    return -self.radius;
                };
                let x = PointState::new(&other, point);
                let (x_u, x_uu) = (other.rotation() * tangent, other.rotation() * bend);
                let gap = c.position - x.position;
                let d = gap.norm();
                let n = gap / d;
                let x_u_dot = perp(x_u) * other.omega;
                let d_uq = -((c.velocity - x.velocity).dot(&x_u) + gap.dot(&x_u_dot)) / d;
                let d_uu = (x_u.norm_squared() - n.dot(&x_u).powi(2)) / d - n.dot(&x_uu);
                if d_uu > 0.0 {
                    envelope = -d_uq * d_uq / d_uu;
                }
                (row, self.radius)
            }
            Against::ProfileFace { profile, normal, .. } => {
                // The face's line on this contact's body; the profile's support point against
                // its normal, found in the profile's body frame.
                let n = circle.rotation() * normal;
                let local = other.rotation().transpose() * n;
                let [point, tangent, bend] = profile.at(profile.support(local));
                let row = line_coordinate(&circle, self.centre, *normal, &other, point).swapped();
                let (x_u, x_uu) = (other.rotation() * tangent, other.rotation() * bend);
                let n_dot = perp(n) * circle.omega;
                let x_u_dot = perp(x_u) * other.omega;
                let f_uq = n_dot.dot(&x_u) + n.dot(&x_u_dot);
                let f_uu = n.dot(&x_uu);
                if f_uu > 0.0 {
                    envelope = -f_uq * f_uq / f_uu;
                }
                (row, 0.0)
            }
            &Against::Line { point, normal, .. } => (
                line_coordinate(&other, point, normal, &circle, self.centre),
                self.radius,
            ),
            &Against::Circle { centre, radius, .. } => match distance(&other, centre, &circle, self.centre) {
                Some(row) => (row, self.radius + radius),
                // Concentric: no direction to part along (a gap of minus both radii).
                None => {
                    out.clear();
                    return -(self.radius + radius);
                }
            },
        };
        out.clear();
        for (body, block) in [(self.other_body(), row.first), (self.body, row.second)] {
            if let BodyRef::Body(id) = body {
                for (k, x) in block.iter().enumerate() {
                    if *x != 0.0 {
                        out.push(id.offset() + k, *x);
                    }
                }
            }
        }
        // C_q q̈ = Q_d: the gap's acceleration is g·q̈ − Q_d (and, on a profile, the closest
        // point's motion along it).
        out.bias = -row.gamma + envelope;
        row.c - reach
    }
}

/// Checks the shapes of a contact of `body`'s circle (or face) of radius `radius` with
/// `against`, naming the contact `name` (rigid or compliant): two different bodies, one of them
/// moving; radii finite and not negative; unit normals; a profile a roller touches at one point
/// (its concave parts rounder than the roller) and a face touches convex.
pub fn check_shapes(name: &str, body: BodyRef, radius: f64, against: &Against) -> Result<(), ModelError> {
    let bad = |what: String| ModelError::InvalidParameter {
        element: format!("force '{name}'"),
        what,
    };
    let other = match *against {
        Against::Line { body, .. }
        | Against::Circle { body, .. }
        | Against::Profile { body, .. }
        | Against::ProfileFace { body, .. } => body,
    };
    if body == BodyRef::Ground && other == BodyRef::Ground {
        return Err(bad("one of the two shapes must be on a moving body".into()));
    }
    if body == other {
        return Err(bad(match against {
            Against::Line { .. } => "the circle and the line are on the same body".into(),
            Against::Circle { .. } => "the two circles are on the same body".into(),
            Against::Profile { .. } => "the circle and the profile are on the same body".into(),
            Against::ProfileFace { .. } => "the face and the profile are on the same body".into(),
        }));
    }
    if let Against::Circle { radius, .. } = *against {
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(bad(format!("radii must be finite and ≥ 0, got {radius}")));
        }
    }
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(bad(format!("radius must be finite and ≥ 0, got {radius}")));
    }
    if let Against::Line { normal, .. } = *against {
        let off_unit = (normal.norm() - 1.0).abs();
        if off_unit.is_nan() || off_unit >= 1e-12 {
            return Err(bad("the line's normal must be a unit vector".into()));
        }
    }
    if let Against::ProfileFace { profile, normal, .. } = against {
        let off_unit = (normal.norm() - 1.0).abs();
        if off_unit.is_nan() || off_unit >= 1e-12 {
            return Err(bad("the face's normal must be a unit vector".into()));
        }
        if let Some((rho, p)) = profile.tightest_concave_radius() {
            return Err(bad(format!(
                "a flat face needs a convex profile: it is concave (radius {rho:.4e} m) near its point ({}, {})",
                p.x, p.y
            )));
        }
    }
    if let Against::Profile { profile, .. } = against {
        if let Some((rho, p)) = profile.tightest_concave_radius() {
            if rho <= radius {
                return Err(bad(format!(
                    "the roller (radius {radius} m) is larger than the profile's concave radius {rho:.4e} m near its point ({}, {}): it would touch the profile at two points",
                    p.x, p.y
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use dalembert_kinematics::BodyId;

    /// An egg-shaped closed profile (convex), 200 points, local to its body.
    pub(crate) fn egg() -> Vec<Vec2> {
        (0..=200)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 200.0;
                let r = 0.08 + 0.015 * (1.0 - a.cos()) + 0.004 * (2.0 * a).sin();
                Vec2::new(r * a.cos(), r * a.sin())
            })
            .collect()
    }

    /// A contact of a shape on body 1 against the egg on body 0.
    fn on_the_egg(radius: f64, against: impl Fn(Profile) -> Against) -> RigidContact {
        RigidContact {
            name: "follower".into(),
            body: BodyRef::Body(BodyId(1)),
            centre: Vec2::new(0.01, -0.02),
            radius,
            against: against(Profile::closed_spline(&egg()).unwrap()),
            restitution: 0.0,
            rest_speed: 1e-3,
            friction: None,
        }
    }

    /// Both bodies move on q(t) = q + v t + a t²/2: the row's rate g·v and its acceleration
    /// g·a + b must be the first and second central differences of the gap along that path
    /// (step 1e-4 s: truncation ~1e-8 of the second difference's scale, round-off 1e-12/h²).
    fn assert_row_is_the_gap_differenced(contact: &RigidContact, q: [f64; 6], what: &str) {
        let v = [0.1, -0.2, 7.0, 0.3, -0.5, -2.0];
        let a = [1.0, 2.0, -30.0, -4.0, 3.0, 15.0];
        let at = |t: f64| -> Vec<f64> { (0..6).map(|i| q[i] + v[i] * t + 0.5 * a[i] * t * t).collect() };
        let mut row = SlipRow::default();
        let s = contact.gap_row(&q, &v, &mut row);
        let (rate, acceleration) = (row.dot(&v), row.dot(&a) + row.bias);
        let h = 1e-4;
        let (sp, sm) = (contact.gap(&at(h)), contact.gap(&at(-h)));
        let (rate_fd, acceleration_fd) = ((sp - sm) / (2.0 * h), (sp - 2.0 * s + sm) / (h * h));
        assert!(
            (rate - rate_fd).abs() < 1e-7 * (1.0 + rate.abs()),
            "{what}: rate {rate} vs {rate_fd}"
        );
        assert!(
            (acceleration - acceleration_fd).abs() < 1e-4 * (1.0 + acceleration.abs()),
            "{what}: acceleration {acceleration} vs {acceleration_fd}"
        );
    }

    #[test]
    fn a_roller_on_a_profile_has_the_gap_rate_and_acceleration_of_its_gap_differenced() {
        // The cam (body 0) and the roller's body (body 1), the roller near the profile, at five
        // cam angles.
        let contact = on_the_egg(0.02, |profile| Against::Profile {
            body: BodyRef::Body(BodyId(0)),
            profile,
        });
        for (k, angle) in [0.3f64, 1.7, 2.9, 4.4, 5.8].into_iter().enumerate() {
            let near = 0.02 + 0.12 * (angle + 0.2).sin() + 0.001 * k as f64;
            let q = [0.002, -0.001, angle, 0.01 + 0.12 * (angle + 0.2).cos(), near, 0.4];
            assert_row_is_the_gap_differenced(&contact, q, &format!("roller at {angle}"));
        }
    }

    #[test]
    fn a_flat_face_on_a_profile_has_the_gap_rate_and_acceleration_of_its_gap_differenced() {
        // The face (body 1, through (0.01, −0.02), normal (0.3, −1)/|…| towards the cam) and the
        // egg (body 0), at five cam angles.
        let normal = Vec2::new(0.3, -1.0).normalize();
        let contact = on_the_egg(0.0, |profile| Against::ProfileFace {
            body: BodyRef::Body(BodyId(0)),
            profile,
            normal,
        });
        for angle in [0.3f64, 1.7, 2.9, 4.4, 5.8] {
            let q = [0.002, -0.001, angle, 0.03, 0.15, 0.2];
            assert_row_is_the_gap_differenced(&contact, q, &format!("face at {angle}"));
        }
    }
}
