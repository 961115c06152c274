//! Compliant contact of two circles, or two segments swept by circles, on two bodies
//! (`docs/contact.md`, "Capsules"): the planar counterparts of the spatial sphere–sphere and
//! capsule–capsule elements, one computation for both.

use super::circle_line::{check, contact_force, point_at};
use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::segment_distance::closest_parameters;
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// Compliant contact of two circles on two bodies (either may be the ground), with the law of
/// [`super::CircleLine`]: they overlap by `δ = Rᵢ + Rⱼ − |cⱼ − cᵢ|` along
/// `n = (cⱼ − cᵢ) / |cⱼ − cᵢ|`, `δ̇ = −n·(ċⱼ − ċᵢ)`; the normal force pushes `j` along `n` and `i`
/// against it at the middle of the overlap, and friction acts on the bodies' relative sliding
/// there.
#[derive(Debug, Clone)]
pub struct CircleCircle {
    /// Element name.
    pub name: String,
    /// The two bodies.
    pub bodies: (BodyRef, BodyRef),
    /// The circles' centres in their bodies' coordinates.
    pub centres: (Vec2, Vec2),
    /// Radii `Rᵢ`, `Rⱼ` (m).
    pub radii: (f64, f64),
    /// The contact law.
    pub law: ContactLaw,
}

/// Compliant contact of two segments swept by circles (rounded segments, the planar capsules) on
/// two bodies (either may be the ground), with the law of [`CircleCircle`] at the closest points
/// of the two segments ([`dalembert_system::segment_distance`]): `δ = Rᵢ + Rⱼ` less the
/// segments' distance. A segment whose ends are one point is a circle.
#[derive(Debug, Clone)]
pub struct SegmentSegment {
    /// Element name.
    pub name: String,
    /// The two bodies.
    pub bodies: (BodyRef, BodyRef),
    /// Each segment's two ends in its body's coordinates.
    pub segments: ([Vec2; 2], [Vec2; 2]),
    /// Radii `Rᵢ`, `Rⱼ` (m).
    pub radii: (f64, f64),
    /// The contact law.
    pub law: ContactLaw,
}

/// What both elements are: two bodies, a segment on each (body coordinates), radii and the law.
struct Pair<'a> {
    bodies: [BodyRef; 2],
    segments: [[Vec2; 2]; 2],
    radii: [f64; 2],
    law: &'a ContactLaw,
}

impl Pair<'_> {
    /// The closest points of the segments as points of their bodies, the overlap `δ` and the
    /// bodies' states at `(q, q̇)`.
    fn geometry(&self, q: &[f64], qd: &[f64]) -> (PointState, PointState, f64, [BodyState; 2]) {
        let states = self.bodies.map(|b| BodyState::of(b, q, qd));
        let ends = [0, 1].map(|k| self.segments[k].map(|e| PointState::new(&states[k], e).position));
        let (s, t) = closest_parameters(ends[0], ends[1]);
        let point = |k: usize, x: f64| {
            let [e0, e1] = self.segments[k];
            PointState::new(&states[k], e0 + x * (e1 - e0))
        };
        let (ci, cj) = (point(0, s), point(1, t));
        let depth = self.radii[0] + self.radii[1] - (cj.position - ci.position).norm();
        (ci, cj, depth, states)
    }

    /// The contact force on the second body (on the first: its opposite), the normal force and
    /// the middle of the overlap as each body's point, or `None` apart (or the segments meeting:
    /// no direction to push along).
    fn load(&self, q: &[f64], qd: &[f64]) -> Option<(Vec2, f64, [PointState; 2])> {
        let (ci, cj, depth, states) = self.geometry(q, qd);
        let d = cj.position - ci.position;
        let length = d.norm();
        if depth <= 0.0 || length == 0.0 {
            return None;
        }
        let n = d / length;
        let normal_force = self.law.normal_force(depth, -n.dot(&(cj.velocity - ci.velocity)));
        let x = ci.position + (self.radii[0] - 0.5 * depth) * n;
        let (xi, xj) = (point_at(&states[0], x), point_at(&states[1], x));
        let force = contact_force(self.law, normal_force, n, xj.velocity - xi.velocity);
        Some((force, normal_force, [xi, xj]))
    }

    fn add_generalized_force(&self, q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        if let Some((force, _, [xi, xj])) = self.load(q, qd) {
            add_point_force(self.bodies[1], &xj, force, q_e);
            add_point_force(self.bodies[0], &xi, -force, q_e);
        }
    }

    /// The resultant: the force on the second body at the middle of the overlap (apart: the
    /// middle of the gap).
    fn resultant(&self, q: &[f64], qd: &[f64]) -> ContactResultant<2> {
        let (ci, cj, depth, _) = self.geometry(q, qd);
        let d = cj.position - ci.position;
        let n = if d.norm() > 0.0 { d / d.norm() } else { Vec2::zeros() };
        let mut out = ContactResultant::new(-depth);
        if let Some((force, normal_force, [_, xj])) = self.load(q, qd) {
            out.add(force.into(), normal_force, xj.position.into());
        }
        out.finish((ci.position + (self.radii[0] - 0.5 * depth) * n).into())
    }

    fn validate(&self, name: &str, count: usize) -> Result<(), ModelError> {
        check_body(name, self.bodies[0], count)?;
        check_body(name, self.bodies[1], count)?;
        if self.bodies[0] == self.bodies[1] {
            return Err(ModelError::InvalidParameter {
                element: format!("force '{name}'"),
                what: "must be between two different bodies".into(),
            });
        }
        if !self.segments.iter().flatten().all(|p| p.iter().all(|x| x.is_finite())) {
            return Err(ModelError::InvalidParameter {
                element: format!("force '{name}'"),
                what: "its points must be finite".into(),
            });
        }
        check(name, &self.radii, self.law)
    }
}

impl CircleCircle {
    fn pair(&self) -> Pair<'_> {
        Pair {
            bodies: [self.bodies.0, self.bodies.1],
            segments: [[self.centres.0; 2], [self.centres.1; 2]],
            radii: [self.radii.0, self.radii.1],
            law: &self.law,
        }
    }
}

impl SegmentSegment {
    fn pair(&self) -> Pair<'_> {
        Pair {
            bodies: [self.bodies.0, self.bodies.1],
            segments: [self.segments.0, self.segments.1],
            radii: [self.radii.0, self.radii.1],
            law: &self.law,
        }
    }
}

/// The [`ForceElement`] of an element that is a [`Pair`].
macro_rules! pair_element {
    ($element:ty) => {
        impl ForceElement for $element {
            fn bodies(&self) -> Option<Vec<BodyRef>> {
                Some(vec![self.bodies.0, self.bodies.1])
            }

            fn name(&self) -> &str {
                &self.name
            }

            fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
                self.pair().add_generalized_force(q, qd, q_e);
            }

            fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
                Some(self.pair().resultant(q, qd))
            }

            /// The elastic part's potential where the two overlap.
            fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
                Some(self.law.potential(self.pair().geometry(q, &[]).2))
            }

            fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
                Some(-self.pair().geometry(q, &[]).2)
            }

            fn is_conservative(&self) -> bool {
                self.law.is_conservative()
            }

            fn validate(&self, count: usize) -> Result<(), ModelError> {
                self.pair().validate(&self.name, count)
            }
        }
    };
}

pair_element!(CircleCircle);
pair_element!(SegmentSegment);
