//! The per-node work of the tree factorization (`super`), written once with the block sizes as
//! constant parameters and instantiated for the pairs of planar and spatial models (a body of 3 or
//! 6 velocities against a group of 1 to 3 or 1 to 6 equations, and the roots), so that the
//! compiler unrolls the small loops, keeps the blocks in registers and drops the bounds checks.
//! [`supported`] says which pairs those are; the tree back end runs only on systems made of them.

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

/// Dispatches `$f::<si, sp>(args…)` for the supported pairs (`sp = 0`: a root); `$otherwise` for
/// any other pair (not reached: [`supported`] is checked when the forest is built).
macro_rules! sized {
    ($f:ident, $si:expr, $sp:expr, $otherwise:expr, $($arg:expr),*) => {
        match ($si, $sp) {
            (1, 0) => $f::<1, 0>($($arg),*),
            (2, 0) => $f::<2, 0>($($arg),*),
            (3, 0) => $f::<3, 0>($($arg),*),
            (4, 0) => $f::<4, 0>($($arg),*),
            (5, 0) => $f::<5, 0>($($arg),*),
            (6, 0) => $f::<6, 0>($($arg),*),
            (3, 1) => $f::<3, 1>($($arg),*),
            (3, 2) => $f::<3, 2>($($arg),*),
            (3, 3) => $f::<3, 3>($($arg),*),
            (1, 3) => $f::<1, 3>($($arg),*),
            (2, 3) => $f::<2, 3>($($arg),*),
            (6, 1) => $f::<6, 1>($($arg),*),
            (6, 2) => $f::<6, 2>($($arg),*),
            (6, 3) => $f::<6, 3>($($arg),*),
            (6, 4) => $f::<6, 4>($($arg),*),
            (6, 5) => $f::<6, 5>($($arg),*),
            (6, 6) => $f::<6, 6>($($arg),*),
            (1, 6) => $f::<1, 6>($($arg),*),
            (2, 6) => $f::<2, 6>($($arg),*),
            (3, 6) => $f::<3, 6>($($arg),*),
            (4, 6) => $f::<4, 6>($($arg),*),
            (5, 6) => $f::<5, 6>($($arg),*),
            _ => $otherwise,
        }
    };
}

/// True when the kernels are instantiated for a node of size `si` under a parent of size `sp`
/// (`0` for a root): bodies of 3 (planar) or 6 (spatial) velocities, groups of at most as many
/// equations as their bodies have velocities (more would be dependent on the child body).
pub(super) fn supported(si: usize, sp: usize) -> bool {
    matches!((si, sp), (1..=6, 0) | (3, 1..=3) | (1..=2, 3) | (6, 1..=6) | (1..=5, 6))
}

/// Factors node `i`'s block `d_i = L_i Δ_i L_iᵀ` (`si × si`, definite of sign `sign`), then, when
/// it has a parent block `d_p` (`sp × sp`), forms `Z_i = L_i⁻¹ K_ip`, `W_i = Δ_i⁻¹ Z_i`,
/// `D_p ← D_p − Z_iᵀ W_i` (lower triangle) and stores `W_i`.
pub(super) fn eliminate(
    si: usize,
    sp: usize,
    sign: f64,
    tolerance: f64,
    di: &mut [f64],
    parent: Option<(Coupling<'_>, &mut [f64], &mut [f64])>,
) -> Result<small_ldlt::Pivots, f64> {
    sized!(eliminate_sized, si, sp, Err(f64::NAN), sign, tolerance, di, parent)
}

#[inline(always)]
fn eliminate_sized<const SI: usize, const SP: usize>(
    sign: f64,
    tolerance: f64,
    di: &mut [f64],
    parent: Option<(Coupling<'_>, &mut [f64], &mut [f64])>,
) -> Result<small_ldlt::Pivots, f64> {
    let mut d = [[0.0f64; SI]; SI];
    d.as_flattened_mut().copy_from_slice(&di[..SI * SI]);
    let pivots = small_ldlt::factor_fixed(&mut d, sign, tolerance)?;
    di[..SI * SI].copy_from_slice(d.as_flattened());
    let Some((k, w, dp)) = parent else { return Ok(pivots) };
    // Z = L⁻¹ K (unit L), row by row.
    let mut z = [[0.0f64; SP]; SI];
    for (r, zr) in z.iter_mut().enumerate() {
        for (c, v) in zr.iter_mut().enumerate() {
            *v = k.at(r, c);
        }
    }
    for r in 1..SI {
        for q in 0..r {
            let l = d[r][q];
            for c in 0..SP {
                z[r][c] -= l * z[q][c];
            }
        }
    }
    let mut wz = [[0.0f64; SP]; SI];
    for r in 0..SI {
        for c in 0..SP {
            wz[r][c] = z[r][c] * d[r][r];
        }
    }
    // Zᵀ W, lower triangle.
    let dp = &mut dp[..SP * SP];
    for a in 0..SP {
        for b in 0..=a {
            let mut v = 0.0;
            for r in 0..SI {
                v += z[r][a] * wz[r][b];
            }
            dp[a * SP + b] -= v;
        }
    }
    w[..SI * SP].copy_from_slice(wz.as_flattened());
    Ok(pivots)
}

/// Children-first half of a tree solve at node `i` (`wc`: `W_i` row by row): `y_i = L_i⁻¹ w_i`, then
/// `w_p −= W_iᵀ y_i`.
pub(super) fn up(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    sized!(up_sized, si, sp, (), l, wc, wi, wp)
}

#[inline(always)]
fn up_sized<const SI: usize, const SP: usize>(l: &[f64], wc: &[f64], wi: &mut [f64], wp: &mut [f64]) {
    let (wi, wp, wc) = (&mut wi[..SI], &mut wp[..SP], &wc[..SI * SP]);
    small_ldlt::forward(&l[..SI * SI], SI, wi);
    for r in 0..SI {
        let v = wi[r];
        for c in 0..SP {
            wp[c] -= wc[r * SP + c] * v;
        }
    }
}

/// Parents-first half of a tree solve at node `i`: `w_i = L_i⁻ᵀ (Δ_i⁻¹ y_i − W_i w_p)`.
pub(super) fn down(si: usize, sp: usize, l: &[f64], wc: &[f64], wi: &mut [f64], wp: &[f64]) {
    sized!(down_sized, si, sp, (), l, wc, wi, wp)
}

#[inline(always)]
fn down_sized<const SI: usize, const SP: usize>(l: &[f64], wc: &[f64], wi: &mut [f64], wp: &[f64]) {
    let (l, wi, wp, wc) = (&l[..SI * SI], &mut wi[..SI], &wp[..SP], &wc[..SI * SP]);
    for r in 0..SI {
        let mut v = wi[r] * l[r * SI + r];
        for c in 0..SP {
            v -= wc[r * SP + c] * wp[c];
        }
        wi[r] = v;
    }
    small_ldlt::backward(l, SI, wi);
}

/// `w_i = D_i⁻¹ w_i` at a root (no parent).
pub(super) fn root(si: usize, l: &[f64], wi: &mut [f64]) {
    small_ldlt::solve(l, si, wi);
}
