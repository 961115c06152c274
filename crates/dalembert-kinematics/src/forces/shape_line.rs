//! Compliant contact of a segment or a polygon on a body with a line of the ground or of another
//! body (`docs/contact.md`): the law of [`super::CircleLine`] at several circles of one radius
//! fixed in the body.
//!
//! - A polygon's vertices (radius 0): a polygon's points nearest a line are always among its
//!   vertices, and an edge lying on the line rests on its two ends.
//! - A segment swept by a radius (a rod with rounded ends): its two end circles, since its points
//!   nearest a line are always on an end cap, and lying flat it rests on both.
//!
//! Each circle that penetrates adds its own normal force and friction; the element's gap is the
//! least of theirs, and its potential the sum of theirs.

use super::circle_line::{press, Line};
use super::{check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// Circles of one radius on a body (a polygon's vertices with radius 0, a segment's ends with its
/// radius) against a line of the ground or of another body.
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
    /// The line: its body, a point and its unit normal in that body's coordinates.
    pub line: Line,
    /// The contact law.
    pub law: ContactLaw,
}

impl ShapeLine {
    /// The states of the shape's body and the line's.
    fn states(&self, q: &[f64], qd: &[f64]) -> (BodyState, BodyState) {
        (BodyState::of(self.body, q, qd), BodyState::of(self.line.body, q, qd))
    }

    /// Each circle's penetration at `q` (negative: the gap).
    fn depths<'a>(&'a self, q: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        let (s, l) = self.states(q, &[]);
        self.centres.iter().map(move |&c| {
            press(
                (self.body, &s),
                (c, self.radius),
                (&self.line, &l),
                &self.law,
                None,
                None,
            )
        })
    }

    /// The deepest circle's penetration `δ` at `q` (negative: the gap).
    pub fn penetration(&self, q: &[f64]) -> f64 {
        self.depths(q).fold(f64::NEG_INFINITY, f64::max)
    }
}

impl ForceElement for ShapeLine {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body, self.line.body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let (s, l) = self.states(q, qd);
        for &c in &self.centres {
            press(
                (self.body, &s),
                (c, self.radius),
                (&self.line, &l),
                &self.law,
                Some(&mut *q_e),
                None,
            );
        }
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let (s, l) = self.states(q, qd);
        let mut out = ContactResultant::new(-self.penetration(q));
        let normal = l.rotation() * self.line.normal;
        let mut deepest = (f64::NEG_INFINITY, Vec2::zeros());
        for &c in &self.centres {
            let depth = press(
                (self.body, &s),
                (c, self.radius),
                (&self.line, &l),
                &self.law,
                None,
                Some(&mut out),
            );
            if depth > deepest.0 {
                let centre = crate::PointState::new(&s, c).position;
                deepest = (depth, centre - self.radius * normal);
            }
        }
        Some(out.finish(deepest.1.into()))
    }

    /// The elastic part's potential of every circle that penetrates.
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        Some(self.depths(q).map(|d| self.law.potential(d)).sum())
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
        if self.centres.is_empty() {
            return bad("needs at least one point".into());
        }
        if self.centres.iter().flat_map(|c| [c.x, c.y]).any(|x| !x.is_finite()) {
            return bad("points must be finite".into());
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return bad(format!("radius must be finite and ≥ 0, got {}", self.radius));
        }
        self.line.check(&self.name, self.body, count)?;
        self.law.check().map_err(|what| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        })
    }
}
