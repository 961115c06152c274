//! The closest points of two segments (`docs/contact.md`, "Capsules"), in the plane or in space:
//! the axes of two capsules or rounded segments, or a sphere's or circle's centre as a segment of
//! zero length.
//!
//! With `P(s) = p₀ + s u` and `Q(t) = q₀ + t w` for `s, t ∈ [0, 1]`, the squared distance
//! `|P(s) − Q(t)|²` is a convex quadratic in `(s, t)`; its minimum over the square is where the
//! unconstrained minimum is, clamped to an edge and minimized along it again. Where the segments
//! are parallel every point of their common stretch is as near as any other: the middle of that
//! stretch is taken, so that a capsule lying along another is pushed at the middle of their
//! overlap (and the point does not jump from one end to the other as the segments turn through
//! parallel).

use nalgebra::SVector;

/// Segments whose directions' cross product is below this share of their lengths' product are
/// parallel (an angle below about 1e-6 rad).
const PARALLEL: f64 = 1e-12;

/// The parameters `(s, t)` of the closest points `p₀ + s (p₁ − p₀)`, `q₀ + t (q₁ − q₀)` of the
/// segments `p₀p₁` and `q₀q₁` (either may have zero length), in `D` dimensions.
pub fn closest_parameters<const D: usize>(p: [SVector<f64, D>; 2], q: [SVector<f64, D>; 2]) -> (f64, f64) {
    let (u, w, r) = (p[1] - p[0], q[1] - q[0], p[0] - q[0]);
    let (a, e, b) = (u.dot(&u), w.dot(&w), u.dot(&w));
    let (c, f) = (u.dot(&r), w.dot(&r));
    let clamp = |x: f64| x.clamp(0.0, 1.0);
    if a == 0.0 && e == 0.0 {
        return (0.0, 0.0);
    }
    if a == 0.0 {
        return (0.0, clamp(f / e));
    }
    if e == 0.0 {
        return (clamp(-c / a), 0.0);
    }
    let denominator = a * e - b * b;
    let s = if denominator > PARALLEL * a * e {
        clamp((b * f - c * e) / denominator)
    } else {
        // Parallel: the middle of the stretch of p₀p₁ that q₀q₁ projects onto, or the end of
        // p₀p₁ nearer to it.
        let (s0, s1) = (-c / a, (b - c) / a);
        let (lo, hi) = (s0.min(s1).max(0.0), s0.max(s1).min(1.0));
        if lo <= hi {
            0.5 * (lo + hi)
        } else {
            clamp(0.5 * (s0 + s1))
        }
    };
    // The nearest point of q₀q₁ to P(s), and then (where that was clamped) of p₀p₁ to it.
    let t = (b * s + f) / e;
    if t < 0.0 {
        (clamp(-c / a), 0.0)
    } else if t > 1.0 {
        (clamp((b - c) / a), 1.0)
    } else {
        (s, t)
    }
}

/// The closest points of the segments `p₀p₁` and `q₀q₁` ([`closest_parameters`]).
pub fn closest_points<const D: usize>(
    p: [SVector<f64, D>; 2],
    q: [SVector<f64, D>; 2],
) -> (SVector<f64, D>, SVector<f64, D>) {
    let (s, t) = closest_parameters(p, q);
    (p[0] + s * (p[1] - p[0]), q[0] + t * (q[1] - q[0]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    type V3 = Vector3<f64>;

    /// The least distance by brute force: the squared distance (smooth where the segments cross)
    /// on a grid of 401 × 401 parameters, then on a grid 50 times finer about the best point, six
    /// times (an independent search, not the algebra above; its last spacing is 1e-12 of the
    /// parameters' range).
    fn searched<const D: usize>(p: [SVector<f64, D>; 2], q: [SVector<f64, D>; 2]) -> f64 {
        let at = |s: f64, t: f64| (p[0] + s * (p[1] - p[0]) - q[0] - t * (q[1] - q[0])).norm_squared();
        let (mut best, mut centre, mut half) = (f64::INFINITY, (0.5, 0.5), 0.5);
        for _ in 0..6 {
            let (cs, ct) = centre;
            for i in 0..=400 {
                for j in 0..=400 {
                    let s = (cs - half + 2.0 * half * i as f64 / 400.0).clamp(0.0, 1.0);
                    let t = (ct - half + 2.0 * half * j as f64 / 400.0).clamp(0.0, 1.0);
                    let d = at(s, t);
                    if d < best {
                        (best, centre) = (d, (s, t));
                    }
                }
            }
            half /= 50.0;
        }
        best.sqrt()
    }

    /// Pseudo-random numbers in [−1, 1) (xorshift from `seed`).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// Two segments, each by its ends.
    type Pair<const D: usize> = ([SVector<f64, D>; 2], [SVector<f64, D>; 2]);

    /// Each pair's closest points are as near as the search finds, within 1e-9 m.
    fn as_near_as_searched<const D: usize>(cases: Vec<Pair<D>>) {
        for (k, (p, q)) in cases.into_iter().enumerate() {
            let (a, b) = closest_points(p, q);
            let (found, best) = ((a - b).norm(), searched(p, q));
            assert!(
                (found - best).abs() < 1e-9,
                "case {k}: found {found}, the search {best}"
            );
        }
    }

    #[test]
    fn the_closest_points_are_as_near_as_a_search_finds() {
        // Crossing, skew with either end clamped, parallel and overlapping, parallel apart, one
        // or both of zero length, and a pseudo-random set: the distance between the points found
        // is the searched least distance within 1e-9 m (the search's last spacing is 1e-12 of the
        // segments' size), and never more than it by more than round-off.
        let v = |x: f64, y: f64, z: f64| V3::new(x, y, z);
        let mut cases = vec![
            (
                [v(-1.0, 0.0, 0.0), v(1.0, 0.0, 0.0)],
                [v(0.0, -1.0, 0.5), v(0.0, 1.0, 0.5)],
            ),
            (
                [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)],
                [v(2.0, -1.0, 0.3), v(2.5, 1.0, 0.7)],
            ),
            (
                [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)],
                [v(-0.5, 0.2, 0.0), v(0.4, 0.2, 0.0)],
            ),
            (
                [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)],
                [v(3.0, 0.2, 0.1), v(2.0, 0.2, 0.1)],
            ),
            (
                [v(0.3, 0.2, 0.1), v(0.3, 0.2, 0.1)],
                [v(-1.0, 0.0, 0.0), v(1.0, 0.5, 0.0)],
            ),
            (
                [v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0)],
                [v(0.5, 0.1, 0.4), v(0.5, 0.1, 0.4)],
            ),
            (
                [v(0.3, 0.2, 0.1), v(0.3, 0.2, 0.1)],
                [v(0.0, 0.0, 1.0), v(0.0, 0.0, 1.0)],
            ),
        ];
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        for _ in 0..40 {
            let mut point = || v(next(), next(), next());
            cases.push(([point(), point()], [point(), point()]));
        }
        as_near_as_searched(cases);
    }

    #[test]
    fn in_the_plane_the_closest_points_are_as_near_as_a_search_finds() {
        // The same in two dimensions, where segments cross (distance 0) as often as not: 40
        // pseudo-random pairs and a parallel one, within 1e-9 m of the search.
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let mut cases = vec![(
            [Vector2::new(0.0, 0.0), Vector2::new(1.0, 0.0)],
            [Vector2::new(0.5, 0.2), Vector2::new(1.5, 0.2)],
        )];
        for _ in 0..40 {
            let mut point = || Vector2::new(next(), next());
            cases.push(([point(), point()], [point(), point()]));
        }
        as_near_as_searched(cases);
    }

    #[test]
    fn parallel_segments_meet_at_the_middle_of_their_common_stretch() {
        // A segment along [0, 1] and another along [0.4, 1.6] above it: every point of [0.4, 1]
        // is nearest; the middle, 0.7, is taken, whichever way either segment runs.
        let v = |x: f64, z: f64| V3::new(x, 0.0, z);
        for p in [[v(0.0, 0.0), v(1.0, 0.0)], [v(1.0, 0.0), v(0.0, 0.0)]] {
            for q in [[v(0.4, 0.3), v(1.6, 0.3)], [v(1.6, 0.3), v(0.4, 0.3)]] {
                let (a, b) = closest_points(p, q);
                assert!((a - v(0.7, 0.0)).norm() < 1e-15, "{a:?}");
                assert!((b - v(0.7, 0.3)).norm() < 1e-15, "{b:?}");
            }
        }
    }
}
