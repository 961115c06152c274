//! Second derivatives of planar point geometry, for the analytic tangent an implicit integrator
//! needs ([`dalembert_system::MultibodySystem::residual_tangent`]).
//!
//! Quantities of two bodies are differentiated with respect to `p = [x_i, y_i, θ_i, x_j, y_j, θ_j]`.
//! With `a = A u` a point's arm, `∂(R + a)/∂θ = perp(a)` and `∂perp(a)/∂θ = −a`, so the only second
//! derivative of a body point is `∂²r/∂θ² = −a` (`docs/equations.md` §1).

use crate::rotation::perp;
use crate::{BodyRef, PointState, Vec2};
use dalembert_system::TangentValues;

/// A symmetric or general 6 × 6 block over the coordinates of two bodies, row-major.
pub type Pair6 = [[f64; 6]; 6];

/// Gradient `g = ∂L/∂p` and Hessian `∂²L/∂p²` of the distance `L = |r_j − r_i|` between two body
/// points (`pi` on the first body, `pj` on the second).
///
/// With `d = r_j − r_i`, `e = d/L` and `G = ∂d/∂p = [−I, −perp(a_i), I, perp(a_j)]`:
/// `g = Gᵀ e`, `∂²L/∂p² = Gᵀ (I − e eᵀ) G / L + e·a_i at (θ_i, θ_i) − e·a_j at (θ_j, θ_j)`
/// (`∂²d/∂θ_i² = a_i`, `∂²d/∂θ_j² = −a_j`). `None` when the points coincide.
pub fn distance_derivatives(pi: &PointState, pj: &PointState) -> Option<([f64; 6], Pair6)> {
    let d = pj.position - pi.position;
    let len = d.norm();
    if len <= f64::MIN_POSITIVE.sqrt() {
        return None;
    }
    let e = d / len;
    let (ti, tj) = (perp(pi.arm), perp(pj.arm));
    // Columns of G, one 2-vector per coordinate.
    let cols = [
        Vec2::new(-1.0, 0.0),
        Vec2::new(0.0, -1.0),
        -ti,
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 1.0),
        tj,
    ];
    let mut g = [0.0; 6];
    let mut h = [[0.0; 6]; 6];
    for a in 0..6 {
        g[a] = e.dot(&cols[a]);
    }
    for a in 0..6 {
        for b in 0..6 {
            // cols[a]ᵀ (I − e eᵀ) cols[b] / L
            h[a][b] = (cols[a].dot(&cols[b]) - g[a] * g[b]) / len;
        }
    }
    h[2][2] += e.dot(&pi.arm);
    h[5][5] -= e.dot(&pj.arm);
    Some((g, h))
}

/// Adds `scale · block` to the tangent at the coordinates of `bodies` (`[first, second]`, either may
/// be the ground, whose rows and columns are skipped): to `∂r/∂q` when `velocity` is false,
/// `∂r/∂v` otherwise.
pub fn add_pair(out: &mut TangentValues<'_>, bodies: [BodyRef; 2], block: &Pair6, scale: f64, velocity: bool) {
    for (sr, br) in bodies.iter().enumerate() {
        let Some(ir) = br.id() else { continue };
        for (sc, bc) in bodies.iter().enumerate() {
            let Some(ic) = bc.id() else { continue };
            for r in 0..3 {
                for c in 0..3 {
                    let v = block[3 * sr + r][3 * sc + c];
                    if v != 0.0 {
                        let (i, j) = (3 * ir.0 + r, 3 * ic.0 + c);
                        if velocity {
                            out.add_v(i, j, scale * v);
                        } else {
                            out.add_q(i, j, scale * v);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BodyState;

    /// The gradient and Hessian of the distance against central differences of `L` (step 1e-5:
    /// truncation ~1e-10, round-off ~1e-11 on quantities of order 1; bound 1e-7).
    #[test]
    fn distance_derivatives_match_finite_differences() {
        let (ui, uj) = (Vec2::new(0.4, -0.3), Vec2::new(-0.2, 0.7));
        let state = |p: &[f64; 6]| {
            let si = BodyState::new(Vec2::new(p[0], p[1]), p[2], Vec2::zeros(), 0.0);
            let sj = BodyState::new(Vec2::new(p[3], p[4]), p[5], Vec2::zeros(), 0.0);
            (PointState::new(&si, ui), PointState::new(&sj, uj))
        };
        let length = |p: &[f64; 6]| {
            let (a, b) = state(p);
            (b.position - a.position).norm()
        };
        let gradient = |p: &[f64; 6]| {
            let (a, b) = state(p);
            distance_derivatives(&a, &b).unwrap().0
        };
        let p0 = [0.1, -0.2, 0.7, 1.3, 0.4, -1.1];
        let (a, b) = state(&p0);
        let (g, h) = distance_derivatives(&a, &b).unwrap();
        let step = 1e-5;
        for k in 0..6 {
            let (mut pp, mut pm) = (p0, p0);
            pp[k] += step;
            pm[k] -= step;
            let fd = (length(&pp) - length(&pm)) / (2.0 * step);
            assert!((fd - g[k]).abs() < 1e-7, "g[{k}] {} vs {fd}", g[k]);
            let (gp, gm) = (gradient(&pp), gradient(&pm));
            for r in 0..6 {
                let fd = (gp[r] - gm[r]) / (2.0 * step);
                assert!((fd - h[r][k]).abs() < 1e-7, "h[{r}][{k}] {} vs {fd}", h[r][k]);
            }
        }
    }
}
