//! The four constraint primitives every spatial joint is built from (Haug, *Computer-Aided
//! Kinematics and Dynamics of Mechanical Systems*, §9.2; Nikravesh §7.2), written in global
//! components with the body-frame angular velocity columns `∂/∂ω' = (∂/∂ω) A`.
//!
//! For a body-fixed arm `s = A s'` the point velocity is `ṙ + ω × s`, so a row `g·(ω × s)` has the
//! angular part `s × g`; the acceleration of a body-fixed vector is `α × s + ω × (ω × s)` with
//! `α = A ω̇'`. Each primitive returns `C`, its Jacobian rows on body `i` and body `j` (`[ṙ; ω]` in
//! global components, converted by the caller), and `Q_d = −(C̈ at v̇ = 0)`:
//!
//! | primitive | `C` | rows `i` / `j` (`ṙ`, `ω`) | `C̈ − C_q v̇` |
//! |---|---|---|---|
//! | point (3) | `P_i − P_j` | `I, s_i × e_k` / `−I, −s_j × e_k` | `ω_i×(ω_i×s_i) − ω_j×(ω_j×s_j)` |
//! | dot-1 | `a_i·a_j − c` | `0, a_i × a_j` / `0, a_j × a_i` | `(ω_i×(ω_i×a_i))·a_j + 2(ω_i×a_i)·(ω_j×a_j) + a_i·(ω_j×(ω_j×a_j))` |
//! | dot-2 | `a_i·d − c`, `d = P_j − P_i` | `−a_i, a_i × (d + s_i)` / `a_i, s_j × a_i` | `(ω_i×(ω_i×a_i))·d + 2(ω_i×a_i)·ḋ + a_i·(ω_j×(ω_j×s_j) − ω_i×(ω_i×s_i))` |
//! | distance | `(d·d − L²)/(2L)` | `−d/L, −(s_i × d)/L` / `d/L, (s_j × d)/L` | `(ḋ·ḋ + d·(ω_j×(ω_j×s_j) − ω_i×(ω_i×s_i)))/L` |
//!
//! Drivers: `Angle` (`sin(θ − f)` as a dot-1 with a rotating vector), `Slide` (dot-2 with value
//! `f(t)`: `C_t = −f'`, `Q_d` gains `f''`), `Coordinate` (`r_k − f(t)`).

use crate::frame::Frame;
use dalembert_system::TimeFunction;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// One scalar equation: value, Jacobian rows on the two ends (global `[ṙ; ω]`), `C_t` and `Q_d`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Row {
    pub c: f64,
    pub c_t: f64,
    pub i: [V3; 2],
    pub j: [V3; 2],
    pub gamma: f64,
}

/// A primitive between end `i` and end `j`, with body-frame data. The last three are drivers
/// (prescribed motions `f(t)`, `f'`, `f''` from a [`TimeFunction`]).
#[derive(Debug, Clone)]
pub(crate) enum Primitive {
    /// `P_i − P_j = 0` (three equations): points `s_i'`, `s_j'`.
    Point { si: V3, sj: V3 },
    /// `a_i · a_j = value`: body-fixed vectors `a_i'`, `a_j'`.
    Dot1 { ai: V3, aj: V3, value: f64 },
    /// `a_i · (P_j − P_i) = value`: vector `a_i'` on `i`, points `s_i'`, `s_j'`.
    Dot2 { ai: V3, si: V3, sj: V3, value: f64 },
    /// `|P_j − P_i| = length`, as `(d·d − L²)/(2L)`.
    Distance { si: V3, sj: V3, length: f64 },
    /// Relative rotation `θ` about `z_i` from `x_i` to `x_j` equal to `f(t)`, as
    /// `C = u·x_j = sin(θ − f)` with the rotating body-`i` vector `u' = cos f y_i' − sin f x_i'`
    /// (no angle unwrapping; `∂C/∂θ = 1` on the solution, so `λ` is the driving torque).
    Angle { xi: V3, yi: V3, xj: V3, f: TimeFunction },
    /// `a_i · (P_j − P_i) = f(t)`: a displacement along `a_i`.
    Slide { ai: V3, si: V3, sj: V3, f: TimeFunction },
    /// Centre-of-mass coordinate `k` of body `j` equal to `f(t)` (`i` is the ground).
    Coordinate { k: usize, f: TimeFunction },
}

impl Primitive {
    /// Number of scalar equations.
    pub fn len(&self) -> usize {
        match self {
            Primitive::Point { .. } => 3,
            _ => 1,
        }
    }

    /// Evaluates the primitive's rows at time `t` into `out` (`len()` of them).
    pub fn evaluate(&self, t: f64, fi: &Frame, fj: &Frame, out: &mut [Row]) {
        match *self {
            Primitive::Point { si, sj } => {
                let (si, sj) = (fi.global(&si), fj.global(&sj));
                let c = fi.r + si - fj.r - sj;
                let quad = fi.centripetal(&si) - fj.centripetal(&sj);
                for (k, row) in out.iter_mut().take(3).enumerate() {
                    let e = V3::ith(k, 1.0);
                    *row = Row {
                        c: c[k],
                        c_t: 0.0,
                        i: [e, si.cross(&e)],
                        j: [-e, -sj.cross(&e)],
                        gamma: -quad[k],
                    };
                }
            }
            Primitive::Dot1 { ai, aj, value } => {
                let (ai, aj) = (fi.global(&ai), fj.global(&aj));
                let (wai, waj) = (fi.w.cross(&ai), fj.w.cross(&aj));
                let quad = fi.centripetal(&ai).dot(&aj) + 2.0 * wai.dot(&waj) + ai.dot(&fj.centripetal(&aj));
                let n = ai.cross(&aj);
                out[0] = Row {
                    c: ai.dot(&aj) - value,
                    c_t: 0.0,
                    i: [V3::zeros(), n],
                    j: [V3::zeros(), -n],
                    gamma: -quad,
                };
            }
            Primitive::Dot2 { ai, si, sj, value } => {
                let (ai, si, sj) = (fi.global(&ai), fi.global(&si), fj.global(&sj));
                let d = fj.r + sj - fi.r - si;
                let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
                let quad = fi.centripetal(&ai).dot(&d)
                    + 2.0 * fi.w.cross(&ai).dot(&d_dot)
                    + ai.dot(&(fj.centripetal(&sj) - fi.centripetal(&si)));
                out[0] = Row {
                    c: ai.dot(&d) - value,
                    c_t: 0.0,
                    i: [-ai, ai.cross(&(d + si))],
                    j: [ai, sj.cross(&ai)],
                    gamma: -quad,
                };
            }
            Primitive::Distance { si, sj, length } => {
                let (si, sj) = (fi.global(&si), fj.global(&sj));
                let d = fj.r + sj - fi.r - si;
                let d_dot = fj.point_velocity(&sj) - fi.point_velocity(&si);
                let inv = 1.0 / length;
                let quad = (d_dot.dot(&d_dot) + d.dot(&(fj.centripetal(&sj) - fi.centripetal(&si)))) * inv;
                out[0] = Row {
                    c: 0.5 * (d.dot(&d) - length * length) * inv,
                    c_t: 0.0,
                    i: [-d * inv, -si.cross(&d) * inv],
                    j: [d * inv, sj.cross(&d) * inv],
                    gamma: -quad,
                };
            }
            Primitive::Angle { xi, yi, xj, ref f } => {
                // u = A_i u'(t), w = A_i du'/df; C̈ − C_q v̇ = the dot-1 terms of (u, x_j) plus
                // 2f'(ω_i × w)·x_j + (f''w − f'²u)·x_j + 2f' w·(ω_j × x_j).
                let [fv, fd, fdd] = f.eval(t);
                let (s, c) = fv.sin_cos();
                let u = fi.global(&(c * yi - s * xi));
                let w = fi.global(&(-s * yi - c * xi));
                let xj = fj.global(&xj);
                let (wu, wx) = (fi.w.cross(&u), fj.w.cross(&xj));
                let quad = fi.centripetal(&u).dot(&xj)
                    + 2.0 * wu.dot(&wx)
                    + u.dot(&fj.centripetal(&xj))
                    + 2.0 * fd * fi.w.cross(&w).dot(&xj)
                    + (fdd * w - fd * fd * u).dot(&xj)
                    + 2.0 * fd * w.dot(&wx);
                let n = u.cross(&xj);
                out[0] = Row {
                    c: u.dot(&xj),
                    c_t: fd * w.dot(&xj),
                    i: [V3::zeros(), n],
                    j: [V3::zeros(), -n],
                    gamma: -quad,
                };
            }
            Primitive::Slide { ai, si, sj, ref f } => {
                let [fv, fd, fdd] = f.eval(t);
                Primitive::Dot2 { ai, si, sj, value: fv }.evaluate(t, fi, fj, out);
                out[0].c_t = -fd;
                out[0].gamma += fdd;
            }
            Primitive::Coordinate { k, ref f } => {
                let [fv, fd, fdd] = f.eval(t);
                let e = V3::ith(k, 1.0);
                out[0] = Row {
                    c: fj.r[k] - fv,
                    c_t: -fd,
                    i: [V3::zeros(), V3::zeros()],
                    j: [e, V3::zeros()],
                    gamma: fdd,
                };
            }
        }
    }
}
