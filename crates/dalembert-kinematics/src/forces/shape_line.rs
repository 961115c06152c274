//! Compliant contact of a segment or a polygon on a body with a line of the ground
//! (`docs/contact.md`): the law of [`super::CircleLine`] at several circles of one radius fixed
//! in the body.
//!
//! - A polygon's vertices (radius 0): a polygon's points nearest a line are always among its
//!   vertices, and an edge lying on the line rests on its two ends.
//! - A segment swept by a radius (a rod with rounded ends): its two end circles, since its points
//!   nearest a line are always on an end cap, and lying flat it rests on both.
//!
//! Each circle that penetrates adds its own normal force and friction; the element's gap is the
//! least of theirs, and its potential the sum of theirs.

use super::circle_line::press;
use super::{check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// Circles of one radius on a body (a polygon's vertices with radius 0, a segment's ends with its
/// radius) against a line of the ground.
#[derive(Debug, Clone)]
pub struct ShapeLine {
    /// Element name.
    pub name: String,
    /// The body carrying the shape.
    pub body: BodyRef,
    /// The circles' centres in body coordinates (at least one).
    pub centres: Vec<Vec2>,
    /// Their radius (m; 0 for a polygon's vertices).
    pub radius: f64,
    /// A point of the line (global).
    pub point: Vec2,
    /// The line's unit normal, out of the ground (global).
    pub normal: Vec2,
    /// The contact law.
    pub law: ContactLaw,
}

impl ShapeLine {
    /// The deepest circle's penetration `δ` at `q` (negative: the gap).
    pub fn penetration(&self, q: &[f64]) -> f64 {
        let s = BodyState::of(self.body, q, &[]);
        self.centres
            .iter()
            .map(|&c| {
                press(
                    (self.body, &s),
                    (c, self.radius),
                    (self.point, self.normal),
                    &self.law,
                    None,
                    None,
                )
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }
}

impl ForceElement for ShapeLine {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let s = BodyState::of(self.body, q, qd);
        for &c in &self.centres {
            press(
                (self.body, &s),
                (c, self.radius),
                (self.point, self.normal),
                &self.law,
                Some(&mut *q_e),
                None,
            );
        }
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let s = BodyState::of(self.body, q, qd);
        let mut out = ContactResultant::new(-self.penetration(q));
        let mut deepest = (f64::NEG_INFINITY, Vec2::zeros());
        for &c in &self.centres {
            let place = (self.point, self.normal);
            let depth = press(
                (self.body, &s),
                (c, self.radius),
                place,
                &self.law,
                None,
                Some(&mut out),
            );
            if depth > deepest.0 {
                let centre = crate::PointState::new(&s, c).position;
                deepest = (depth, centre - self.radius * self.normal);
            }
        }
        Some(out.finish(deepest.1.into()))
    }

    /// The elastic part's potential of every circle that penetrates.
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        let s = BodyState::of(self.body, q, &[]);
        let line = (self.point, self.normal);
        Some(
            self.centres
                .iter()
                .map(|&c| {
                    self.law
                        .potential(press((self.body, &s), (c, self.radius), line, &self.law, None, None))
                })
                .sum(),
        )
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(-self.penetration(q))
    }

    fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }

    fn validate(&self, count: usize) -> Result<(), ModelError> {
        check_body(&self.name, self.body, count)?;
        let bad = |what: String| {
            Err(ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what,
            })
        };
        if self.body == BodyRef::Ground {
            return bad("acts on the ground: give it a moving body".into());
        }
        if self.centres.is_empty() {
            return bad("needs at least one point".into());
        }
        let coordinates = self.centres.iter().flat_map(|c| [c.x, c.y]);
        let line = [self.point.x, self.point.y, self.normal.x, self.normal.y];
        if coordinates.chain(line).any(|x| !x.is_finite()) {
            return bad("points, the line's point and normal must be finite".into());
        }
        if (self.normal.norm() - 1.0).abs() > 1e-12 {
            return bad(format!(
                "the line's normal must be a unit vector, got length {}",
                self.normal.norm()
            ));
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return bad(format!("radius must be finite and ≥ 0, got {}", self.radius));
        }
        self.law.check().map_err(|what| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        })
    }
}
