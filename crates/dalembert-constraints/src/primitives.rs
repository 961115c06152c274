//! Scalar constraint equations shared by the joints and drivers.
//!
//! Each primitive returns a [`Row`]: the value, both Jacobian blocks, `C_t` and `Q_d` of one scalar
//! equation. Body kinematics follow `docs/equations.md` §1 with `A_θ u = perp(A u)`; the quadratic
//! part of a point's acceleration is `−θ̇² A u`. `Q_d` is minus the part of `C̈` that does not
//! contain `q̈`, plus the driver's `f''(t)`.

use dalembert_kinematics::rotation::perp;
use dalembert_kinematics::second_derivatives::Pair6;
use dalembert_kinematics::{rotation, BodyState, PointState, Vec2};

/// One scalar constraint equation evaluated at a state.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Row {
    /// Residual.
    pub c: f64,
    /// `C_t`.
    pub c_t: f64,
    /// `Q_d`.
    pub gamma: f64,
    /// `∂C/∂[x, y, θ]` of the first body.
    pub first: [f64; 3],
    /// `∂C/∂[x, y, θ]` of the second body.
    pub second: [f64; 3],
}

impl Row {
    /// Subtracts a driving function `f(t)` given as `[f, f', f'']`: `C ← C − f`, `C_t ← C_t − f'`,
    /// `Q_d ← Q_d + f''`.
    #[inline]
    pub fn drive(mut self, f: [f64; 3]) -> Row {
        self.c -= f[0];
        self.c_t -= f[1];
        self.gamma += f[2];
        self
    }

    /// Swaps the roles of the two bodies' Jacobian blocks.
    #[inline]
    pub fn swapped(mut self) -> Row {
        std::mem::swap(&mut self.first, &mut self.second);
        self
    }
}

/// Component `axis` (0 = x, 1 = y) of `p_i − p_j` for points `u_i` on `first`, `u_j` on `second`:
/// `C = (R_i + A_i u_i − R_j − A_j u_j)·e_axis`, `Q_d = (A_i u_i θ̇_i² − A_j u_j θ̇_j²)·e_axis`.
pub fn point_coincidence(first: &BodyState, u_i: Vec2, second: &BodyState, u_j: Vec2) -> [Row; 2] {
    let pi = PointState::new(first, u_i);
    let pj = PointState::new(second, u_j);
    let d = pi.position - pj.position;
    let g = -(pi.quadratic_acceleration - pj.quadratic_acceleration);
    let (ti, tj) = (pi.d_theta(), pj.d_theta());
    [
        Row {
            c: d.x,
            c_t: 0.0,
            gamma: g.x,
            first: [1.0, 0.0, ti.x],
            second: [-1.0, 0.0, -tj.x],
        },
        Row {
            c: d.y,
            c_t: 0.0,
            gamma: g.y,
            first: [0.0, 1.0, ti.y],
            second: [0.0, -1.0, -tj.y],
        },
    ]
}

/// The coordinate of point `u_o` of body `other` along the body-fixed direction `w_local` of body
/// `line`, measured from the line's point `u_l`: `s = wᵀ (p_o − p_l)`, `w = A_l w_local`.
///
/// ```text
/// ∂s/∂R_l = −wᵀ      ∂s/∂θ_l = perp(w)ᵀ d − wᵀ perp(A_l u_l)
/// ∂s/∂R_o =  wᵀ      ∂s/∂θ_o = wᵀ perp(A_o u_o)
/// Q_d = −(ẅ₀ᵀ d + 2 ẇᵀ ḋ + wᵀ d̈₀),   ẇ = θ̇_l perp(w),  ẅ₀ = −θ̇_l² w
/// ```
///
/// The returned row has `first` = the line body and `second` = the other body.
pub fn line_coordinate(line: &BodyState, u_l: Vec2, w_local: Vec2, other: &BodyState, u_o: Vec2) -> Row {
    let pl = PointState::new(line, u_l);
    let po = PointState::new(other, u_o);
    let w = rotation(line.angle) * w_local;
    let wp = perp(w);
    let d = po.position - pl.position;
    let dd = po.velocity - pl.velocity;
    let dd0 = po.quadratic_acceleration - pl.quadratic_acceleration;
    let wdot = wp * line.omega;
    let wddot0 = -w * (line.omega * line.omega);
    let s_dd0 = wddot0.dot(&d) + 2.0 * wdot.dot(&dd) + w.dot(&dd0);
    Row {
        c: w.dot(&d),
        c_t: 0.0,
        gamma: -s_dd0,
        first: [-w.x, -w.y, wp.dot(&d) - w.dot(&pl.d_theta())],
        second: [w.x, w.y, w.dot(&po.d_theta())],
    }
}

/// Relative angle `C = θ_j − ratio · θ_i` (add the offset with [`Row::drive`]).
pub fn relative_angle(first: &BodyState, second: &BodyState, ratio: f64) -> Row {
    angle_row(first.angle, second.angle, ratio)
}

/// [`relative_angle`] from the two angles alone (the row needs neither position nor rotation).
pub fn angle_row(first: f64, second: f64, ratio: f64) -> Row {
    Row {
        c: second - ratio * first,
        c_t: 0.0,
        gamma: 0.0,
        first: [0.0, 0.0, -ratio],
        second: [0.0, 0.0, 1.0],
    }
}

/// Distance `s = |p_j − p_i|` between point `u_i` on `first` and `u_j` on `second`.
///
/// With `d = p_j − p_i`, `e = d/|d|`: `∂s/∂p_j = eᵀ = −∂s/∂p_i`,
/// `Q_d = −(eᵀ d̈₀ + (|ḋ|² − (eᵀ ḋ)²)/|d|)`. Returns `None` when the points coincide (the
/// distance is not differentiable there).
pub fn distance(first: &BodyState, u_i: Vec2, second: &BodyState, u_j: Vec2) -> Option<Row> {
    let pi = PointState::new(first, u_i);
    let pj = PointState::new(second, u_j);
    let d = pj.position - pi.position;
    let len = d.norm();
    if len <= f64::MIN_POSITIVE.sqrt() {
        return None;
    }
    let e = d / len;
    let dd = pj.velocity - pi.velocity;
    let dd0 = pj.quadratic_acceleration - pi.quadratic_acceleration;
    let ed = e.dot(&dd);
    let s_dd0 = e.dot(&dd0) + (dd.norm_squared() - ed * ed) / len;
    Some(Row {
        c: len,
        c_t: 0.0,
        gamma: -s_dd0,
        first: [-e.x, -e.y, -e.dot(&pi.d_theta())],
        second: [e.x, e.y, e.dot(&pj.d_theta())],
    })
}

/// A unit vector along `v`, or `None` when `v` is zero or not finite.
pub fn unit(v: Vec2) -> Option<Vec2> {
    let n = v.norm();
    (n.is_finite() && n > 0.0).then(|| v / n)
}

/// Second derivatives of the primitives, weighted by a multiplier each, over
/// `[x_i, y_i, θ_i, x_j, y_j, θ_j]` of the primitive's `first` and `second` body
/// (`dalembert_kinematics::second_derivatives`). They give `∂(C_qᵀ λ)/∂q` for implicit integrators.
pub mod hessian {
    use super::*;

    /// `λ_x ∂²C_x + λ_y ∂²C_y` of [`point_coincidence`]: `−λ·(A_i u_i)` at `(θ_i, θ_i)`,
    /// `λ·(A_j u_j)` at `(θ_j, θ_j)`.
    pub fn point_coincidence(first: &BodyState, u_i: Vec2, second: &BodyState, u_j: Vec2, lambda: [f64; 2]) -> Pair6 {
        let l = Vec2::new(lambda[0], lambda[1]);
        let mut h = [[0.0; 6]; 6];
        h[2][2] = -l.dot(&PointState::new(first, u_i).arm);
        h[5][5] = l.dot(&PointState::new(second, u_j).arm);
        h
    }

    /// `λ ∂²s` of [`line_coordinate`] (`first` = the line body `l`, `second` = the other `o`):
    ///
    /// ```text
    /// ∂²s/∂R_l∂θ_l = −perp(w)   ∂²s/∂R_o∂θ_l = perp(w)   ∂²s/∂θ_l² = −w·d − w·a_l
    /// ∂²s/∂θ_l∂θ_o = w·a_o      ∂²s/∂θ_o² = −w·a_o        (a = A u, d = p_o − p_l)
    /// ```
    pub fn line_coordinate(
        line: &BodyState,
        u_l: Vec2,
        w_local: Vec2,
        other: &BodyState,
        u_o: Vec2,
        lambda: f64,
    ) -> Pair6 {
        let pl = PointState::new(line, u_l);
        let po = PointState::new(other, u_o);
        let w = rotation(line.angle) * w_local;
        let wp = perp(w);
        let d = po.position - pl.position;
        let mut h = [[0.0; 6]; 6];
        for k in 0..2 {
            h[k][2] = -wp[k];
            h[2][k] = -wp[k];
            h[3 + k][2] = wp[k];
            h[2][3 + k] = wp[k];
        }
        h[2][2] = -w.dot(&d) - w.dot(&pl.arm);
        h[2][5] = w.dot(&po.arm);
        h[5][2] = h[2][5];
        h[5][5] = -w.dot(&po.arm);
        scaled(h, lambda)
    }

    /// `λ ∂²s` of [`distance`] (`None` where the points coincide).
    pub fn distance(first: &BodyState, u_i: Vec2, second: &BodyState, u_j: Vec2, lambda: f64) -> Option<Pair6> {
        let pi = PointState::new(first, u_i);
        let pj = PointState::new(second, u_j);
        let (_, h) = dalembert_kinematics::second_derivatives::distance_derivatives(&pi, &pj)?;
        Some(scaled(h, lambda))
    }

    /// The second derivatives of an equation linear in the coordinates (relative angle, body
    /// coordinate): none.
    pub fn linear() -> Pair6 {
        [[0.0; 6]; 6]
    }

    /// `h` with the two bodies' roles exchanged (for a row built with [`Row::swapped`]).
    pub fn swapped(h: Pair6) -> Pair6 {
        let mut out = [[0.0; 6]; 6];
        for (r, row) in h.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                out[(r + 3) % 6][(c + 3) % 6] = *v;
            }
        }
        out
    }

    /// `a + b`.
    pub fn sum(mut a: Pair6, b: &Pair6) -> Pair6 {
        for (ra, rb) in a.iter_mut().zip(b) {
            for (x, y) in ra.iter_mut().zip(rb) {
                *x += y;
            }
        }
        a
    }

    fn scaled(mut h: Pair6, s: f64) -> Pair6 {
        h.iter_mut().flatten().for_each(|v| *v *= s);
        h
    }
}
