//! Compliant contact of two convex polygons on two planar bodies (`docs/contact.md`, "Polygons
//! against polygons"): each vertex of one that is inside the other is pushed out through the
//! other's nearest edge, by the law of [`super::CircleLine`] with radius 0 against that edge's
//! line on the other body ([`super::Line`]).
//!
//! A vertex `v` inside a convex polygon with edges through `pₑ` with outward unit normals `nₑ` is
//! `δ = minₑ (−nₑ·(v − pₑ)) > 0` deep; the edge reaching the minimum is the one it is pushed
//! through, and the force is the gradient of `k δⁿ⁺¹ / (n + 1)` on both bodies (as for a line on
//! a moving body). Two convex polygons that overlap always have a vertex of one inside the other
//! unless they cross (a plus sign), which they reach only through a vertex first; the element's
//! gap is the least over the vertices of `maxₑ nₑ·(v − pₑ)` (positive outside).

use super::circle_line::{press, Line};
use super::{check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// A convex polygon on a body: its vertices counter-clockwise and its edges' lines, in the body's
/// coordinates, and the radius of a circle about its first vertex that holds it.
#[derive(Debug, Clone)]
pub struct ConvexPolygon {
    /// The body.
    pub body: BodyRef,
    vertices: Vec<Vec2>,
    /// Each edge's line: its first vertex and its outward unit normal.
    edges: Vec<Line>,
    reach: f64,
}

impl ConvexPolygon {
    /// The polygon with `vertices` (body coordinates, either way round) on `body`; `Err` with
    /// the reason where they are fewer than three, not finite, or not a convex polygon.
    pub fn new(body: BodyRef, vertices: &[Vec2]) -> Result<Self, String> {
        if vertices.len() < 3 {
            return Err(format!(
                "a polygon needs at least three vertices, got {}",
                vertices.len()
            ));
        }
        if vertices.iter().any(|v| !(v.x.is_finite() && v.y.is_finite())) {
            return Err("the vertices must be finite".into());
        }
        let n = vertices.len();
        let turn = |k: usize| {
            let (a, b, c) = (vertices[k], vertices[(k + 1) % n], vertices[(k + 2) % n]);
            let (u, w) = (b - a, c - b);
            u.x * w.y - u.y * w.x
        };
        let turns: Vec<f64> = (0..n).map(turn).collect();
        let scale = vertices.iter().map(|v| (v - vertices[0]).norm()).fold(0.0, f64::max);
        let tiny = 1e-12 * scale * scale;
        let (left, right) = (turns.iter().all(|t| *t > tiny), turns.iter().all(|t| *t < -tiny));
        if !(left || right) {
            return Err(
                "the vertices are not a convex polygon (each must turn the same way, none in line with its neighbours)"
                    .into(),
            );
        }
        let mut vertices = vertices.to_vec();
        if right {
            vertices.reverse();
        }
        let edges = (0..n)
            .map(|k| {
                let d = vertices[(k + 1) % n] - vertices[k];
                Line {
                    body,
                    point: vertices[k],
                    normal: Vec2::new(d.y, -d.x) / d.norm(),
                }
            })
            .collect();
        Ok(ConvexPolygon {
            body,
            vertices,
            edges,
            reach: scale,
        })
    }

    /// The vertices, counter-clockwise, in the body's coordinates.
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }
}

/// Two convex polygons on two bodies (either may be the ground) in compliant contact.
#[derive(Debug, Clone)]
pub struct PolygonPair {
    /// Element name.
    pub name: String,
    /// The two polygons.
    pub polygons: [ConvexPolygon; 2],
    /// The contact law.
    pub law: ContactLaw,
}

/// What to do at each vertex inside the other polygon.
enum Visit<'a> {
    /// Nothing: the least gap only.
    Gap,
    /// Add the generalized forces.
    Forces(&'a mut [f64]),
    /// Add to the resultant (the force on the second body).
    Resultant(&'a mut ContactResultant<2>),
    /// Add each vertex's potential `k δⁿ⁺¹ / (n + 1)`.
    Potential(&'a mut f64),
}

impl PolygonPair {
    /// Visits every vertex of each polygon inside the other (`visit`), and returns the least gap
    /// of any vertex.
    fn sweep(&self, q: &[f64], qd: &[f64], mut visit: Visit<'_>) -> f64 {
        let states = self.polygons.each_ref().map(|p| BodyState::of(p.body, q, qd));
        // Apart when the circles that hold them are: their first vertices' distance less the
        // reaches (a gap of the right sign, not the distance).
        let first = [0, 1].map(|k| PointState::new(&states[k], self.polygons[k].vertices[0]).position);
        let apart = (first[1] - first[0]).norm() - self.polygons[0].reach - self.polygons[1].reach;
        if apart > 0.0 {
            return apart;
        }
        let mut gap = f64::INFINITY;
        for (k, sign) in [(0, -1.0), (1, 1.0)] {
            let (mine, other) = (&self.polygons[k], &self.polygons[1 - k]);
            let (s, so) = (&states[k], &states[1 - k]);
            for &v in &mine.vertices {
                let x = PointState::new(s, v).position;
                // The edge the vertex is least deep behind (most outside of).
                let (mut outside, mut edge) = (f64::NEG_INFINITY, &other.edges[0]);
                for e in &other.edges {
                    let n = so.rotation() * e.normal;
                    let d = n.dot(&(x - PointState::new(so, e.point).position));
                    if d > outside {
                        (outside, edge) = (d, e);
                    }
                }
                gap = gap.min(outside);
                if outside >= 0.0 {
                    continue;
                }
                let at = ((mine.body, s), (v, 0.0), (edge, so));
                match &mut visit {
                    Visit::Gap => {}
                    Visit::Potential(total) => **total += self.law.potential(-outside),
                    Visit::Forces(q_e) => {
                        press(at.0, at.1, at.2, &self.law, Some(&mut **q_e), None);
                    }
                    Visit::Resultant(r) => {
                        // The force on the first polygon's body is the opposite of the second's.
                        let before = r.force;
                        press(at.0, at.1, at.2, &self.law, None, Some(&mut **r));
                        if sign < 0.0 {
                            for i in 0..2 {
                                r.force[i] = before[i] - (r.force[i] - before[i]);
                            }
                        }
                    }
                }
            }
        }
        gap
    }
}

impl ForceElement for PolygonPair {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.polygons[0].body, self.polygons[1].body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        self.sweep(q, qd, Visit::Forces(q_e));
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let mut out = ContactResultant::new(0.0);
        out.gap = self.sweep(q, qd, Visit::Resultant(&mut out));
        let s = BodyState::of(self.polygons[1].body, q, qd);
        let centre = PointState::new(&s, self.polygons[1].vertices[0]).position;
        Some(out.finish(centre.into()))
    }

    /// `k δⁿ⁺¹ / (n + 1)` of every vertex inside the other polygon.
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        let mut total = 0.0;
        self.sweep(q, &[], Visit::Potential(&mut total));
        Some(total)
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(self.sweep(q, &[], Visit::Gap))
    }

    fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }

    fn validate(&self, count: usize) -> Result<(), ModelError> {
        let [a, b] = &self.polygons;
        check_body(&self.name, a.body, count)?;
        check_body(&self.name, b.body, count)?;
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        };
        if a.body == b.body {
            return Err(bad("must be between two different bodies".into()));
        }
        self.law.check().map_err(bad)
    }
}
