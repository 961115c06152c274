//! Compliant contact of a sphere on a body with a plane fixed to the ground or to another body,
//! and of two spheres or capsules on two bodies (`docs/contact.md`).
//!
//! With the sphere's centre `c`, radius `R`, the plane's point `p₀` and unit normal `n` (out of
//! the solid), the penetration is `δ = R − n·(c − p₀)` and its rate `δ̇ = −n·(ċ − v)`, `v` the
//! velocity of the plane's body's point at `c` (zero for the ground's). Where `δ > 0` the plane
//! pushes at the sphere's lowest point `x = c − R n` with
//!
//! ```text
//! F_n = k δⁿ (1 + d δ̇)   (Hunt–Crossley; clamped at 0: the plane never pulls)        (K1)
//! F_t = −μ F_n v_t / max(|v_t|, v_s)                                                  (K2)
//! ```
//!
//! `v_t` is the velocity of the body's point at `x` along the plane, relative to the plane's body's
//! point there; the plane's body feels the opposite force at `x` (the gradient of the potential
//! below on both bodies: `docs/contact.md`, "A line or plane on a moving body"). Above the smoothing velocity
//! `v_s` (m/s) the friction is Coulomb's `μ F_n` against the sliding; below it grows linearly with
//! `v_t`, so that a body at rest on a slope creeps at a speed below `v_s` instead of sticking.
//! With `d = 0` and `μ = 0` the element is conservative with the potential `k δⁿ⁺¹ / (n + 1)`.
//!
//! A box or a capsule on a plane is the same law at several spheres of one body: a box's eight
//! corners (radius 0: the lowest points of a box are always among its corners, and a face or an
//! edge flat on the plane rests on its corners, as MuJoCo's box–plane contact does), a capsule's
//! two end caps (its segment's ends with its radius: a capsule's lowest point is always on an
//! end cap, and lying flat it rests on both). Each sphere that penetrates adds its own (K1) and
//! (K2); the element's gap is the least of the spheres'.
//!
//! Two spheres (centres `cᵢ`, `cⱼ`, radii `Rᵢ`, `Rⱼ`) overlap by `δ = Rᵢ + Rⱼ − |cⱼ − cᵢ|` along
//! `n = (cⱼ − cᵢ) / |cⱼ − cᵢ|`, `δ̇ = −n·(ċⱼ − ċᵢ)`; the same (K1) pushes `j` along `n` and `i`
//! against it at the middle of the overlap, and (K2) acts on the relative sliding there. Two
//! capsules are the same with `cᵢ`, `cⱼ` the closest points of their axes ([`dalembert_system::segment_distance`]):
//! `δ` is then `Rᵢ + Rⱼ` less the distance of the segments, whose change is `n` at those points
//! (they are nearest, so moving them along the axes changes the distance by nothing to first
//! order), so the force is still the gradient of `k δⁿ⁺¹ / (n + 1)` and the rate still
//! `−n·(ċⱼ − ċᵢ)` with `ċ` the velocities of the axes' material points there. A sphere is a
//! capsule whose two ends are one point.

use super::{add_point_force, V3};
use crate::frame::Frame;
use dalembert_system::segment_distance::closest_parameters;
use dalembert_system::{ContactLaw, ContactResultant};

/// Two spheres swept along segments (capsules; a sphere's segment has zero length) on two
/// bodies (either may be the ground).
#[derive(Debug, Clone)]
pub(crate) struct SweptPair {
    /// The bodies (`None`: the ground) and their segments' ends in their frames.
    pub ends: [(Option<usize>, [V3; 2]); 2],
    /// Radii `Rᵢ`, `Rⱼ` (m).
    pub radii: [f64; 2],
    /// The law.
    pub law: ContactLaw,
}

impl SweptPair {
    /// The frames, the closest points of the segments (global) and their arms from the body
    /// origins, and the overlap `δ`.
    fn geometry(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> ([Frame; 2], [V3; 2], [V3; 2], f64) {
        let frames = [frame(self.ends[0].0), frame(self.ends[1].0)];
        // The ends' arms from the body origins, and the ends.
        let ends = [0, 1].map(|k| self.ends[k].1.map(|e| frames[k].global(&e)));
        let points = [0, 1].map(|k| ends[k].map(|arm| frames[k].r + arm));
        let (s, t) = closest_parameters(points[0], points[1]);
        let arms = [(0, s), (1, t)].map(|(k, x)| ends[k][0] + x * (ends[k][1] - ends[k][0]));
        let centres = [0, 1].map(|k| frames[k].r + arms[k]);
        let depth = self.radii[0] + self.radii[1] - (centres[1] - centres[0]).norm();
        (frames, arms, centres, depth)
    }

    /// The contact force on the second body (on the first: its opposite), where it acts
    /// (global) and the two bodies' frames, or `None` apart (or concentric: no direction to push
    /// along).
    fn load(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> Option<(V3, V3, [Frame; 2])> {
        let ([fi, fj], [si, sj], [ci, cj], depth) = self.geometry(frame);
        let d = cj - ci;
        let length = d.norm();
        if depth <= 0.0 || length == 0.0 {
            return None;
        }
        let n = d / length;
        let rate = -n.dot(&(fj.point_velocity(&sj) - fi.point_velocity(&si)));
        let normal_force = self.law.normal_force(depth, rate);
        // The middle of the overlap, as an arm of each body.
        let x = ci + (self.radii[0] - 0.5 * depth) * n;
        let (ai, aj) = (x - fi.r, x - fj.r);
        let slip = fj.point_velocity(&aj) - fi.point_velocity(&ai);
        let (sliding, speed) = sliding_speed(&slip, &n);
        let force = normal_force * n - self.law.friction_factor(normal_force, speed) * sliding;
        Some((force, x, [fi, fj]))
    }

    /// Adds the contact force's generalized forces on both bodies.
    pub fn add(&self, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let Some((force, x, frames)) = self.load(frame) else {
            return;
        };
        for ((end, f), sign) in self.ends.iter().zip(&frames).zip([-1.0, 1.0]) {
            if let Some(b) = end.0 {
                add_point_force(out, b, f, &(x - f.r), &(sign * force));
            }
        }
    }

    /// The contact's resultant at the state behind `frame` (`docs/contact.md`, "Output"): the
    /// force on the second body, its normal part, and the middle of the overlap (where the
    /// spheres are apart: the middle of the gap between their surfaces).
    pub fn resultant(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> ContactResultant<3> {
        let (_, _, [ci, cj], depth) = self.geometry(frame);
        let d = cj - ci;
        let n = if d.norm() > 0.0 { d / d.norm() } else { V3::zeros() };
        let mut out = ContactResultant::new(-depth);
        if let Some((force, point, _)) = self.load(frame) {
            out.add(force.into(), force.dot(&n), point.into());
        }
        out.finish((ci + (self.radii[0] - 0.5 * depth) * n).into())
    }

    /// The overlap `δ` at the state behind `frame` (negative: the gap).
    pub fn overlap(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        self.geometry(frame).3
    }

    /// `k δⁿ⁺¹ / (n + 1)` where the spheres overlap.
    pub fn potential(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        self.law.potential(self.overlap(frame))
    }

    /// True without dissipation and friction.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }
}

/// Spheres of one radius on a body against a plane of the ground or of another body (one sphere,
/// a capsule's two end caps, a box's eight corners with radius 0).
#[derive(Debug, Clone)]
pub(crate) struct SpherePlane {
    /// The body.
    pub body: usize,
    /// The spheres' centres in the body frame.
    pub centres: Vec<V3>,
    /// Radius `R` (m; 0 for a box's corners).
    pub radius: f64,
    /// The plane's body (`None`: the ground).
    pub plane_body: Option<usize>,
    /// A point of the plane, in its body's frame.
    pub point: V3,
    /// The plane's unit normal, out of the solid, in its body's frame.
    pub normal: V3,
    /// The law.
    pub law: ContactLaw,
}

/// The plane placed with its body's frame: its global point and unit normal.
struct Placed {
    frame: Frame,
    point: V3,
    normal: V3,
}

impl Placed {
    /// The penetration `δ` of a sphere of radius `radius` centred at `centre` (global).
    fn depth(&self, radius: f64, centre: &V3) -> f64 {
        radius - self.normal.dot(&(centre - self.point))
    }
}

impl SpherePlane {
    /// The body's frame and the plane placed at the state behind `frame`.
    fn frames(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> (Frame, Placed) {
        let plane = frame(self.plane_body);
        let placed = Placed {
            point: plane.point(&self.point),
            normal: plane.global(&self.normal),
            frame: plane,
        };
        (frame(Some(self.body)), placed)
    }

    /// The deepest sphere's penetration `δ` at the state behind `frame` (negative: the gap).
    pub fn penetration(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let (f, plane) = self.frames(frame);
        self.centres
            .iter()
            .map(|c| plane.depth(self.radius, &f.point(c)))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Calls `visit(x, force, normal force)` for each penetrating sphere's contact force (K1,
    /// K2): its global force on the body at the global point `x` (the plane's body feels its
    /// opposite there).
    fn each(&self, f: &Frame, plane: &Placed, visit: &mut dyn FnMut(&V3, &V3, f64)) {
        let n = plane.normal;
        let p = &plane.frame;
        for c in &self.centres {
            let s_centre = f.global(c);
            let centre = f.r + s_centre;
            let depth = plane.depth(self.radius, &centre);
            if depth <= 0.0 {
                continue;
            }
            let rate = -n.dot(&(f.point_velocity(&s_centre) - p.point_velocity(&(centre - p.r))));
            let normal_force = self.law.normal_force(depth, rate);
            let x = centre - self.radius * n;
            let slip = f.point_velocity(&(x - f.r)) - p.point_velocity(&(x - p.r));
            let (sliding, speed) = sliding_speed(&slip, &n);
            let force = normal_force * n - self.law.friction_factor(normal_force, speed) * sliding;
            visit(&x, &force, normal_force);
        }
    }

    /// Adds each penetrating sphere's contact force's generalized forces on both bodies (K1, K2).
    pub fn add(&self, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let (f, plane) = self.frames(frame);
        self.each(&f, &plane, &mut |x, force, _| {
            add_point_force(out, self.body, &f, &(x - f.r), force);
            if let Some(b) = self.plane_body {
                add_point_force(out, b, &plane.frame, &(x - plane.frame.r), &(-force));
            }
        });
    }

    /// The contact's resultant at the state behind `frame` (`docs/contact.md`, "Output"): the
    /// sum of the spheres' forces on the body, of their normal forces, and their centre of
    /// pressure (the contact points weighted by their normal forces; out of contact, or where
    /// the normal forces vanish, the deepest sphere's lowest point).
    pub fn resultant(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> ContactResultant<3> {
        let (f, plane) = self.frames(frame);
        let mut out = ContactResultant::new(-self.penetration(frame));
        self.each(&f, &plane, &mut |x, load, n| out.add((*load).into(), n, (*x).into()));
        let deepest = self
            .centres
            .iter()
            .map(|c| f.point(c))
            .max_by(|a, b| plane.depth(self.radius, a).total_cmp(&plane.depth(self.radius, b)))
            .unwrap_or(f.r);
        out.finish((deepest - self.radius * plane.normal).into())
    }

    /// `Σ k δⁿ⁺¹ / (n + 1)` over the spheres that penetrate.
    pub fn potential(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let (f, plane) = self.frames(frame);
        self.centres
            .iter()
            .map(|c| self.law.potential(plane.depth(self.radius, &f.point(c))))
            .sum()
    }

    /// True without dissipation and friction.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }
}

/// The part of `v` along the plane of normal `n`, and its length.
fn sliding_speed(v: &V3, n: &V3) -> (V3, f64) {
    let sliding = v - n.dot(v) * n;
    let speed = sliding.norm();
    (sliding, speed)
}
