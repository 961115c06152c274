//! The per-node work of the tree factorization (`super`), written once for any block sizes and
//! inlined into copies specialised for the sizes of planar and spatial models (a body of 3 or 6
//! velocities against a group of 1 to 6 equations), so that the compiler unrolls the small loops.

use crate::linalg::small_ldlt;

/// The block `K_ip` between a node and its parent, read from the Jacobian values: for the group
/// side, equation `r` on the body's coordinate `c` is `jac[edge[r] + c]`; for the body side the
/// transpose.
#[derive(Clone, Copy)]
pub(super) struct Coupling<'a> {
    pub jac: &'a [f64],
    pub edge: &'a [usize],
    pub group_side: bool,
}

impl Coupling<'_> {
    #[inline(always)]
    fn at(&self, r: usize, c: usize) -> f64 {
        if self.group_side {
            self.jac[self.edge[r] + c]
        } else {
            self.jac[self.edge[c] + r]
        }
    }
}

/// Dispatches `$f(si, sp, args…)` to a copy with literal sizes for the usual pairs.
macro_rules! sized {
    ($f:ident, $si:expr, $sp:expr, $($arg:expr),*) => {
        match ($si, $sp) {
            (3, 1) => $f(3, 1, $($arg),*),
            (3, 2) => $f(3, 2, $($arg),*),
            (3, 3) => $f(3, 3, $($arg),*),
            (1, 3) => $f(1, 3, $($arg),*),
            (2, 3) => $f(2, 3, $($arg),*),
            (6, 1) => $f(6, 1, $($arg),*),
            (6, 3) => $f(6, 3, $($arg),*),
            (6, 4) => $f(6, 4, $($arg),*),
            (6, 5) => $f(6, 5, $($arg),*),
            (6, 6) => $f(6, 6, $($arg),*),
            (1, 6) => $f(1, 6, $($arg),*),
            (3, 6) => $f(3, 6, $($arg),*),
            (4, 6) => $f(4, 6, $($arg),*),
            (5, 6) => $f(5, 6, $($arg),*),
            (si, sp) => $f(si, sp, $($arg),*),
        }
    };
}

/// Factors node `i`'s block `d_i = L_i Δ_i L_iᵀ` (`si × si`, definite of sign `sign`), then, when
/// it has a parent block `d_p` (`sp × sp`), forms `Z_i = L_i⁻¹ K_ip`, `D_p ← D_p − Z_iᵀ Δ_i⁻¹ Z_i`
/// (lower triangle) and stores `W_i = Δ_i⁻¹ Z_i`.
pub(super) fn eliminate(
    si: usize,
    sp: usize,
    sign: f64,
    tolerance: f64,
    di: &mut [f64],
    parent: Option<(Coupling<'_>, &mut [f64], &mut [f64])>,
) -> Result<small_ldlt::Pivots, f64> {
    sized!(eliminate_sized, si, sp, sign, tolerance, di, parent)
}

#[inline(always)]
fn eliminate_sized(
    si: usize,
    sp: usize,
    sign: f64,
    tolerance: f64,
    di: &mut [f64],
    parent: Option<(Coupling<'_>, &mut [f64], &mut [f64])>,
) -> Result<small_ldlt::Pivots, f64> {
    let di = &mut di[..si * si];
    let pivots = small_ldlt::factor(di, si, sign, tolerance)?;
    let Some((k, w, dp)) = parent else { return Ok(pivots) };
    let (w, dp) = (&mut w[..si * sp], &mut dp[..sp * sp]);
    // Z = L⁻¹ K (unit L), row by row into `w`.
    for r in 0..si {
        for c in 0..sp {
            let mut v = k.at(r, c);
            for q in 0..r {
                v -= di[r * si + q] * w[q * sp + c];
            }
            w[r * sp + c] = v;
        }
    }
    for a in 0..sp {
        for b in 0..=a {
            let mut v = 0.0;
            for r in 0..si {
                v += w[r * sp + a] * w[r * sp + b] * di[r * si + r];
            }
            dp[a * sp + b] -= v;
        }
    }
    for r in 0..si {
        let inv = di[r * si + r];
        for c in 0..sp {
            w[r * sp + c] *= inv;
        }
    }
    Ok(pivots)
}

/// Children-first half of a tree solve at node `i` (`wc`: `W_i` row by row): `y_i = L_i⁻¹ w_i`, then
/// `w_p −= W_iᵀ y_i`.
pub(super) fn up(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    sized!(up_sized, si, sp, l, wc, wi, wp)
}

#[inline(always)]
fn up_sized(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    let (wi, wp, wc) = (&mut wi[..si], &mut wp[..sp], &wc[..si * sp]);
    small_ldlt::forward(l, si, wi);
    for r in 0..si {
        let v = wi[r];
        for c in 0..sp {
            wp[c] -= wc[r * sp + c] * v;
        }
    }
}

/// Parents-first half of a tree solve at node `i`: `w_i = L_i⁻ᵀ (Δ_i⁻¹ y_i − W_i w_p)`.
pub(super) fn down(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &[f64]) {
    sized!(down_sized, si, sp, l, wc, wi, wp)
}

#[inline(always)]
fn down_sized(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &[f64]) {
    let (wi, wp, wc) = (&mut wi[..si], &wp[..sp], &wc[..si * sp]);
    for r in 0..si {
        let mut v = wi[r] * l[r * si + r];
        for c in 0..sp {
            v -= wc[r * sp + c] * wp[c];
        }
        wi[r] = v;
    }
    small_ldlt::backward(l, si, wi);
}

/// `w_i = D_i⁻¹ w_i` at a root (no parent).
pub(super) fn root(si: usize, l: &[f64], wi: &mut [f64]) {
    small_ldlt::solve(l, si, wi);
}
