//! The per-node work of the tree factorization (`super`), written once for any block sizes and
//! inlined into copies specialised for the sizes of planar and spatial models (a body of 3 or 6
//! velocities against a group of 1 to 6 equations), so that the compiler unrolls the small loops.

use crate::linalg::small_cholesky;

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

/// Factors node `i`'s block `d_i` (`si × si`, sign `sign`), then, when it has a parent block
/// `d_p` (`sp × sp`), forms `Z_i = L_i⁻¹ K_ip` and `D_p ← D_p − sign Z_iᵀ Z_i` (lower triangle).
pub(super) fn eliminate(
    si: usize,
    sp: usize,
    sign: f64,
    tolerance: f64,
    di: &mut [f64],
    parent: Option<(Coupling<'_>, &mut [f64], &mut [f64])>,
) -> Result<small_cholesky::Pivots, f64> {
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
) -> Result<small_cholesky::Pivots, f64> {
    let di = &mut di[..si * si];
    let pivots = small_cholesky::factor(di, si, sign, tolerance)?;
    let Some((k, z, dp)) = parent else { return Ok(pivots) };
    let (z, dp) = (&mut z[..si * sp], &mut dp[..sp * sp]);
    for r in 0..si {
        for c in 0..sp {
            let mut v = k.at(r, c);
            for q in 0..r {
                v -= di[r * si + q] * z[q * sp + c];
            }
            z[r * sp + c] = v * di[r * si + r];
        }
    }
    for a in 0..sp {
        for b in 0..=a {
            let mut v = 0.0;
            for r in 0..si {
                v += z[r * sp + a] * z[r * sp + b];
            }
            dp[a * sp + b] -= sign * v;
        }
    }
    Ok(pivots)
}

/// Children-first half of a tree solve at node `i`: `y_i = L_i⁻¹ w_i`, then `w_p −= sign Z_iᵀ y_i`.
pub(super) fn up(si: usize, sp: usize, sign: f64, l: &[f64], z: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    sized!(up_sized, si, sp, sign, l, z, wi, wp)
}

#[inline(always)]
fn up_sized(si: usize, sp: usize, sign: f64, l: &[f64], z: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    let (wi, wp, z) = (&mut wi[..si], &mut wp[..sp], &z[..si * sp]);
    small_cholesky::forward(l, si, wi);
    for r in 0..si {
        let v = sign * wi[r];
        for c in 0..sp {
            wp[c] -= z[r * sp + c] * v;
        }
    }
}

/// Parents-first half of a tree solve at node `i`: `w_i = sign L_i⁻ᵀ (y_i − Z_i w_p)`.
pub(super) fn down(si: usize, sp: usize, sign: f64, l: &[f64], z: &[f64], wi: &mut [f64], wp: &[f64]) {
    sized!(down_sized, si, sp, sign, l, z, wi, wp)
}

#[inline(always)]
fn down_sized(si: usize, sp: usize, sign: f64, l: &[f64], z: &[f64], wi: &mut [f64], wp: &[f64]) {
    let (wi, wp, z) = (&mut wi[..si], &wp[..sp], &z[..si * sp]);
    for r in 0..si {
        let mut v = wi[r];
        for c in 0..sp {
            v -= z[r * sp + c] * wp[c];
        }
        wi[r] = v;
    }
    small_cholesky::backward(l, si, wi);
    if sign < 0.0 {
        wi.iter_mut().for_each(|v| *v = -*v);
    }
}

/// `w_i = sign L_i⁻ᵀ L_i⁻¹ w_i` at a root (no parent).
pub(super) fn root(si: usize, sign: f64, l: &[f64], wi: &mut [f64]) {
    small_cholesky::solve(l, si, sign, wi);
}
