//! A closed planar curve fixed in a body: a cam's profile through given points, as a periodic
//! cubic spline (`docs/limits.md`, "A roller on a cam profile").
//!
//! The `N` points `P_k` (local to the body, the last one closing the curve onto the first) are
//! knots at `u = 0, 1, …, N − 1`; segment `k` runs from `P_k` to `P_{k+1}` (indices modulo `N`),
//! with `t = u − k ∈ [0, 1]`:
//!
//! ```text
//! S(t)   = (1 − t) P_k + t P_{k+1} + ((1 − t)³ − (1 − t)) M_k / 6 + (t³ − t) M_{k+1} / 6
//! S'(t)  = P_{k+1} − P_k + (1 − 3 (1 − t)²) M_k / 6 + (3 t² − 1) M_{k+1} / 6
//! S''(t) = (1 − t) M_k + t M_{k+1}
//! M_{k−1} + 4 M_k + M_{k+1} = 6 (P_{k+1} − 2 P_k + P_{k−1})   (periodic: C² all round)
//! ```
//!
//! The second derivatives `M_k` are solved once (the cyclic system is diagonally dominant:
//! Gauss–Seidel halves the error per sweep). The closest point of the curve to a point is found
//! from the nearest knot by a safeguarded Newton iteration on `u`.

use dalembert_kinematics::Vec2;

/// A closed curve through points, local to a body.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    points: Vec<Vec2>,
    second: Vec<Vec2>,
}

/// The fewest distinct points of a profile.
pub const PROFILE_POINTS: usize = 4;

impl Profile {
    /// The periodic cubic spline through `points` (local to the body), whose last point must
    /// repeat the first (the curve is closed there); an error says what is wrong: too few
    /// points, not closed, a point not finite, two consecutive points equal, or a curve that
    /// crosses itself.
    pub fn closed_spline(points: &[Vec2]) -> Result<Self, String> {
        if let Some(k) = points.iter().position(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(format!("point {} of the profile is not finite", k + 1));
        }
        let (Some(first), Some(last)) = (points.first(), points.last()) else {
            return Err("the profile has no points".into());
        };
        let size = points.iter().fold(0.0f64, |s, p| s.max((p - first).norm()));
        if (last - first).norm() > 1e-9 * size.max(f64::MIN_POSITIVE) || points.len() < 2 {
            return Err(format!(
                "the profile is not closed: its last point ({}, {}) must repeat its first ({}, {})",
                last.x, last.y, first.x, first.y
            ));
        }
        let points: Vec<Vec2> = points[..points.len() - 1].to_vec();
        let n = points.len();
        if n < PROFILE_POINTS {
            return Err(format!(
                "a profile needs at least {PROFILE_POINTS} distinct points (and the first repeated at the end), got {n}"
            ));
        }
        for k in 0..n {
            if (points[(k + 1) % n] - points[k]).norm() <= 1e-12 * size {
                return Err(format!(
                    "points {} and {} of the profile coincide",
                    k + 1,
                    (k + 1) % n + 1
                ));
            }
        }
        // A simple curve: no two segments of the polygon cross (O(N²), once).
        for i in 0..n {
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                if segments_cross(points[i], points[(i + 1) % n], points[j], points[(j + 1) % n]) {
                    return Err(format!(
                        "the profile crosses itself (between points {} and {}, and {} and {})",
                        i + 1,
                        i + 2,
                        j + 1,
                        (j + 1) % n + 1
                    ));
                }
            }
        }
        let rhs: Vec<Vec2> = (0..n)
            .map(|k| 6.0 * (points[(k + 1) % n] - 2.0 * points[k] + points[(k + n - 1) % n]))
            .collect();
        let mut second = vec![Vec2::zeros(); n];
        let scale = rhs.iter().fold(0.0f64, |s, r| s.max(r.norm()));
        for _ in 0..200 {
            let mut change = 0.0f64;
            for k in 0..n {
                let m = (rhs[k] - second[(k + n - 1) % n] - second[(k + 1) % n]) / 4.0;
                change = change.max((m - second[k]).norm());
                second[k] = m;
            }
            if change <= 1e-16 * scale {
                break;
            }
        }
        Ok(Profile { points, second })
    }

    /// The number of knots `N` (the parameter runs over `[0, N)`).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// False: a profile has at least [`PROFILE_POINTS`] knots.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The knots (local to the body), without the repeated last point.
    pub fn points(&self) -> &[Vec2] {
        &self.points
    }

    /// `S(u)`, `S'(u)`, `S''(u)` at parameter `u` (taken modulo `N`).
    pub fn at(&self, u: f64) -> [Vec2; 3] {
        let n = self.points.len();
        let u = u.rem_euclid(n as f64);
        let k = (u.floor() as usize).min(n - 1);
        let t = u - k as f64;
        let (p0, p1) = (self.points[k], self.points[(k + 1) % n]);
        let (m0, m1) = (self.second[k], self.second[(k + 1) % n]);
        let s = 1.0 - t;
        let position = s * p0 + t * p1 + ((s * s * s - s) * m0 + (t * t * t - t) * m1) / 6.0;
        let tangent = p1 - p0 + ((1.0 - 3.0 * s * s) * m0 + (3.0 * t * t - 1.0) * m1) / 6.0;
        let curvature = s * m0 + t * m1;
        [position, tangent, curvature]
    }

    /// The parameter of the curve's point closest to `c` (local to the body): from the nearest
    /// knot, Newton's method on `φ(u) = |S(u) − c|² / 2` kept within the knot's two segments
    /// (bisection where a step leaves them or `φ''` is not positive).
    pub fn closest(&self, c: Vec2) -> f64 {
        let start = self.lowest_knot(|p| (p - c).norm_squared());
        self.minimize(start, |[s, ds, dds]| {
            let d = s - c;
            (d.dot(&ds), ds.norm_squared() + d.dot(&dds))
        })
    }

    /// The parameter of the curve's support point against `direction` (local): the point
    /// where `direction·S(u)` is least, the first a flat face moving along `−direction` meets.
    pub fn support(&self, direction: Vec2) -> f64 {
        let start = self.lowest_knot(|p| direction.dot(&p));
        self.minimize(start, |[_, ds, dds]| (direction.dot(&ds), direction.dot(&dds)))
    }

    /// The knot where `f` is least.
    fn lowest_knot(&self, f: impl Fn(Vec2) -> f64) -> f64 {
        (0..self.points.len())
            .min_by(|&i, &j| f(self.points[i]).total_cmp(&f(self.points[j])))
            .unwrap_or(0) as f64
    }

    /// A minimum of a function of `u` near the knot `start`, given its first and second
    /// derivatives from `S`, `S'`, `S''`: Newton's method kept within the knot's two segments
    /// (bisection where a step leaves them or the second derivative is not positive).
    fn minimize(&self, start: f64, derivatives: impl Fn([Vec2; 3]) -> (f64, f64)) -> f64 {
        let (mut lo, mut hi) = (start - 1.0, start + 1.0);
        let mut u = start;
        for _ in 0..60 {
            let (slope, bend) = derivatives(self.at(u));
            if slope > 0.0 {
                hi = u;
            } else {
                lo = u;
            }
            let newton = u - slope / bend;
            let next = if bend > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            let step = (next - u).abs();
            u = next;
            if step <= 1e-15 * (1.0 + u.abs()) || hi - lo <= 1e-15 * (1.0 + u.abs()) {
                break;
            }
        }
        u
    }

    /// Twice the signed area enclosed (positive: the points run anticlockwise).
    pub fn twice_area(&self) -> f64 {
        let n = self.points.len();
        (0..n)
            .map(|k| {
                let (a, b) = (self.points[k], self.points[(k + 1) % n]);
                a.x * b.y - a.y * b.x
            })
            .sum()
    }

    /// The smallest radius of curvature (m) where the curve is concave (bends away from its
    /// inside), over the knots and segment midpoints, with the point (local) where it is; `None`
    /// for a convex curve.
    pub fn tightest_concave_radius(&self) -> Option<(f64, Vec2)> {
        let orientation = self.twice_area().signum();
        (0..2 * self.points.len())
            .filter_map(|k| {
                let [p, d1, d2] = self.at(0.5 * k as f64);
                let bend = orientation * (d1.x * d2.y - d1.y * d2.x);
                (bend < 0.0).then(|| (d1.norm().powi(3) / -bend, p))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

/// True when segments `ab` and `cd` cross (touching ends do not count).
fn segments_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let side = |p: Vec2, q: Vec2, r: Vec2| (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
    let (d1, d2) = (side(a, b, c), side(a, b, d));
    let (d3, d4) = (side(c, d, a), side(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(radius: f64, n: usize) -> Vec<Vec2> {
        (0..=n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                Vec2::new(radius * a.cos(), radius * a.sin())
            })
            .collect()
    }

    #[test]
    fn a_spline_through_a_circles_points_is_the_circle() {
        // 360 points on a circle of 0.1 m (h = 1.7 mm between knots): the periodic cubic
        // spline's errors go as h⁴, h³ and h² (measured 1.4e-11 m, 4.2e-8 rad, 3.2e-6 of the
        // curvature 1/R; bars 1e-10, 1e-6, 1e-4). The closest point to a point 0.5 m out lies on
        // the spline's normal through it, so the tangent's error moves it along the curve by
        // about R × 4e-8 (bar 1e-8 m); its distance, which a gap is, to second order only.
        let p = Profile::closed_spline(&circle(0.1, 360)).unwrap();
        let mut worst = [0.0f64; 3];
        for k in 0..720 {
            let u = 0.5 * k as f64 + 0.25;
            let [s, ds, dds] = p.at(u);
            worst[0] = worst[0].max((s.norm() - 0.1).abs());
            worst[1] = worst[1].max(s.dot(&ds).abs() / (ds.norm() * 0.1));
            let curvature = (ds.x * dds.y - ds.y * dds.x) / ds.norm().powi(3);
            worst[2] = worst[2].max((curvature - 10.0).abs() / 10.0);
        }
        assert!(worst[0] < 1e-10, "off the circle by {:e} m", worst[0]);
        assert!(worst[1] < 1e-6, "tangent off by {:e} rad", worst[1]);
        assert!(worst[2] < 1e-4, "curvature off by {:e}", worst[2]);
        assert!(p.tightest_concave_radius().is_none());
        let c = Vec2::new(0.3, 0.4);
        let [s, _, _] = p.at(p.closest(c));
        let expected = c / c.norm() * 0.1;
        assert!((s - expected).norm() < 1e-8, "closest {s:?}, expected {expected:?}");
        assert!(((s - c).norm() - 0.4).abs() < 1e-10);
    }

    #[test]
    fn bad_profiles_are_refused_with_what_is_wrong() {
        let mut open = circle(0.1, 12);
        open.pop();
        assert!(Profile::closed_spline(&open).unwrap_err().contains("not closed"));
        let few = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0),
        ];
        assert!(Profile::closed_spline(&few).unwrap_err().contains("at least 4"));
        let bow = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0),
        ];
        assert!(Profile::closed_spline(&bow).unwrap_err().contains("crosses itself"));
    }
}
