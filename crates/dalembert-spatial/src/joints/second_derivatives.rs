//! Second derivatives of the joint primitives (`super::primitives`): how the constraint wrench
//! `C_qᵀ λ` of each primitive changes with the poses of its two ends, for the analytic tangent an
//! implicit integrator needs (`dalembert_system::MultibodySystem::residual_tangent`).

use super::primitives::Primitive;
use crate::frame::Frame;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

type M3 = nalgebra::Matrix3<f64>;

/// The constraint wrench of one primitive, `C_qᵀ λ` on its two ends in global terms (force `F` and
/// torque `T` on `i` and on `j`), and its derivatives with respect to the ends' global
/// displacements `r` and small global rotations `θ` (a body-fixed global vector `s` moves by
/// `δθ × s`, so `∂s/∂θ = −[s]×`).
///
/// `d[row][col]`: rows `F_i, T_i, F_j, T_j`, columns `r_i, θ_i, r_j, θ_j`. The caller maps the
/// rotations to body-frame perturbations and the torques to body-frame components.
/// Force elements use the same form (`crate::forces`), with `dv`: the derivatives with respect to
/// the ends' global velocities `v` and angular velocities `ω` (columns `v_i, ω_i, v_j, ω_j`; zero for
/// constraints).
#[derive(Debug, Clone, Copy)]
pub(crate) struct WrenchDerivative {
    pub d: [[M3; 4]; 4],
    pub dv: [[M3; 4]; 4],
    /// `T_i`, `T_j` (global).
    pub torque: [V3; 2],
}

/// `[v]×`.
pub(crate) fn skew(v: &V3) -> M3 {
    v.cross_matrix()
}

impl WrenchDerivative {
    pub(crate) fn zero() -> Self {
        WrenchDerivative {
            d: [[M3::zeros(); 4]; 4],
            dv: [[M3::zeros(); 4]; 4],
            torque: [V3::zeros(); 2],
        }
    }

    /// `T_i = λ a_i × a_j = −T_j` (dot-1, and the angle driver with its rotating vector):
    /// `∂(a_i × a_j)/∂θ_i = [a_j]× [a_i]×`, `∂/∂θ_j = −[a_i]× [a_j]×`.
    fn dot1(ai: &V3, aj: &V3, lambda: f64) -> Self {
        let mut w = Self::zero();
        let n = ai.cross(aj) * lambda;
        w.torque = [n, -n];
        let di = skew(aj) * skew(ai) * lambda;
        let dj = -skew(ai) * skew(aj) * lambda;
        w.d[1][1] = di;
        w.d[1][3] = dj;
        w.d[3][1] = -di;
        w.d[3][3] = -dj;
        w
    }

    /// `F_i = −λ a_i = −F_j`, `T_i = λ a_i × e` (`e = d + s_i = r_j + s_j − r_i`), `T_j = λ s_j × a_i`
    /// (dot-2, and the slide driver).
    fn dot2(ai: &V3, si: &V3, sj: &V3, d: &V3, lambda: f64) -> Self {
        let mut w = Self::zero();
        let e = d + si;
        w.torque = [ai.cross(&e) * lambda, sj.cross(ai) * lambda];
        let (sa, se, ss) = (skew(ai), skew(&e), skew(sj));
        w.d[0][1] = sa * lambda;
        w.d[2][1] = -sa * lambda;
        w.d[1][0] = -sa * lambda;
        w.d[1][1] = se * sa * lambda;
        w.d[1][2] = sa * lambda;
        w.d[1][3] = -sa * ss * lambda;
        w.d[3][1] = -ss * sa * lambda;
        w.d[3][3] = sa * ss * lambda;
        w
    }

    /// Derivatives of `λ C_qᵀ` of primitive `p` at time `t` between frames `fi`, `fj`, for its
    /// multipliers `lambda` (`p.len()` of them).
    pub fn of(p: &Primitive, t: f64, fi: &Frame, fj: &Frame, lambda: &[f64]) -> Self {
        match *p {
            Primitive::Point { si, sj } => {
                let (si, sj) = (fi.global(&si), fj.global(&sj));
                let l = V3::new(lambda[0], lambda[1], lambda[2]);
                let mut w = Self::zero();
                w.torque = [si.cross(&l), -sj.cross(&l)];
                w.d[1][1] = skew(&l) * skew(&si);
                w.d[3][3] = -skew(&l) * skew(&sj);
                w
            }
            Primitive::Dot1 { ai, aj, .. } => Self::dot1(&fi.global(&ai), &fj.global(&aj), lambda[0]),
            Primitive::Dot2 { ai, si, sj, .. } | Primitive::Slide { ai, si, sj, .. } => {
                let (ai, si, sj) = (fi.global(&ai), fi.global(&si), fj.global(&sj));
                let d = fj.r + sj - fi.r - si;
                Self::dot2(&ai, &si, &sj, &d, lambda[0])
            }
            Primitive::Distance { si, sj, length } => {
                let (si, sj) = (fi.global(&si), fj.global(&sj));
                let d = fj.r + sj - fi.r - si;
                let k = lambda[0] / length;
                let mut w = Self::zero();
                w.torque = [-si.cross(&d) * k, sj.cross(&d) * k];
                let dd = [-M3::identity(), skew(&si), M3::identity(), -skew(&sj)];
                let (sd, ssi, ssj) = (skew(&d), skew(&si), skew(&sj));
                for c in 0..4 {
                    w.d[2][c] = dd[c] * k;
                    w.d[0][c] = -dd[c] * k;
                    // T_j = k s_j × d: k (−[d]× ∂s_j + [s_j]× ∂d), ∂s_j/∂θ_j = −[s_j]×.
                    let dsj = if c == 3 { -ssj } else { M3::zeros() };
                    w.d[3][c] = (-sd * dsj + ssj * dd[c]) * k;
                    let dsi = if c == 1 { -ssi } else { M3::zeros() };
                    w.d[1][c] = -(-sd * dsi + ssi * dd[c]) * k;
                }
                w
            }
            Primitive::Angle { xi, yi, xj, ref f } => {
                let fv = f.eval(t)[0];
                let (s, c) = fv.sin_cos();
                let u = fi.global(&(c * yi - s * xi));
                Self::dot1(&u, &fj.global(&xj), lambda[0])
            }
            Primitive::Coordinate { .. } => Self::zero(),
        }
    }
}

/// Adds `sign` times the wrench derivative `wd` of an element between `ends` (body and frame; the
/// ground's rows and columns are skipped) to the tangent, in the velocity coordinates `(v, ω')`:
/// a body-frame rotation `δ'` of body `k` is the global `A_k δ'`, `ω = A_k ω'`, and a body-frame
/// torque `A_bᵀ T` changes by `A_bᵀ dT + [A_bᵀ T]× δ'_b`. `sign` is `+1` for `C_qᵀ λ`, `−1` for an
/// applied force (the residual holds `−Q`).
pub(crate) fn add_wrench(
    out: &mut dalembert_system::TangentValues<'_>,
    ends: [(Option<usize>, &Frame); 2],
    wd: &WrenchDerivative,
    sign: f64,
) {
    use crate::frame::NV;
    for (e, (body_e, frame_e)) in ends.iter().enumerate() {
        let Some(b) = *body_e else { continue };
        let at = frame_e.a.transpose();
        for (k, (body_k, frame_k)) in ends.iter().enumerate() {
            let Some(c) = *body_k else { continue };
            let own = if e == k {
                skew(&(at * wd.torque[e]))
            } else {
                M3::zeros()
            };
            for (velocity, d) in [(false, &wd.d), (true, &wd.dv)] {
                let blocks = [
                    d[2 * e][2 * k],
                    d[2 * e][2 * k + 1] * frame_k.a,
                    at * d[2 * e + 1][2 * k],
                    at * d[2 * e + 1][2 * k + 1] * frame_k.a + if velocity { M3::zeros() } else { own },
                ];
                for (blk, (ro, co)) in blocks.iter().zip([(0, 0), (0, 3), (3, 0), (3, 3)]) {
                    for r in 0..3 {
                        for cc in 0..3 {
                            let x = sign * blk[(r, cc)];
                            if x != 0.0 {
                                let (i, j) = (NV * b + ro + r, NV * c + co + cc);
                                if velocity {
                                    out.add_v(i, j, x);
                                } else {
                                    out.add_q(i, j, x);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
