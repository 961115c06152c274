//! Unblocked dense Cholesky of a small symmetric definite matrix stored row by row, in place: the
//! Schur complement of small systems and the blocks of the tree factorization. Allocates nothing.
//!
//! `sign` selects the definiteness: `+1` factors a positive definite `A = L Lᵀ`, `−1` a negative
//! definite one as `−A = L Lᵀ` (the multiplier blocks of a saddle-point matrix).

/// The pivots of a factorization by [`factor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pivots {
    /// Smallest pivot `l_kk`.
    pub min: f64,
    /// Largest pivot `l_kk`.
    pub max: f64,
    /// Smallest `l_kk² / (sign · a_kk)`: how much of each diagonal entry survived elimination, a
    /// measure of near-singularity unchanged by a diagonal scaling of `A` (`1` for a diagonal
    /// matrix; its inverse is a lower bound of the condition number of the equilibrated `A`).
    pub decay: f64,
}

/// Factors `sign · A` (`n × n`, row-major, lower triangle read) into `L` in the lower triangle,
/// with the reciprocals `1 / l_kk` on the diagonal (solves multiply instead of divide: a division's
/// latency dominated the substitutions of the tree factorization's small blocks).
///
/// Returns the pivots; fails with the offending pivot `d` (before its square root) when
/// `d ≤ tolerance · max_k sign · a_kk`, i.e. when `A` is not definite to that relative tolerance.
#[inline(always)]
pub fn factor(a: &mut [f64], n: usize, sign: f64, tolerance: f64) -> Result<Pivots, f64> {
    let mut largest = 0.0f64;
    for i in 0..n {
        largest = largest.max(sign * a[i * n + i]);
    }
    let (mut lmin, mut lmax, mut decay) = (f64::INFINITY, 0.0f64, 1.0f64);
    for j in 0..n {
        let diagonal = sign * a[j * n + j];
        let mut d = diagonal;
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        // Also rejects NaN.
        if d.is_nan() || d <= tolerance * largest {
            return Err(d);
        }
        decay = decay.min(d / diagonal);
        let d = d.sqrt();
        lmin = lmin.min(d);
        lmax = lmax.max(d);
        let inv = 1.0 / d;
        a[j * n + j] = inv;
        for i in j + 1..n {
            let mut v = sign * a[i * n + j];
            for k in 0..j {
                v -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = v * inv;
        }
    }
    Ok(Pivots {
        min: lmin,
        max: lmax,
        decay,
    })
}

/// `x ← A⁻¹ x` with the factor of [`factor`] (same `sign`).
#[inline(always)]
pub fn solve(l: &[f64], n: usize, sign: f64, x: &mut [f64]) {
    forward(l, n, x);
    backward(l, n, x);
    if sign < 0.0 {
        x[..n].iter_mut().for_each(|v| *v = -*v);
    }
}

/// `x ← L⁻¹ x` (forward substitution with the factor of [`factor`]).
#[inline(always)]
pub fn forward(l: &[f64], n: usize, x: &mut [f64]) {
    for i in 0..n {
        let row = &l[i * n..i * n + i + 1];
        let mut v = x[i];
        for (a, b) in row[..i].iter().zip(&x[..i]) {
            v -= a * b;
        }
        x[i] = v * row[i];
    }
}

/// `x ← L⁻ᵀ x` (back substitution with the factor of [`factor`]).
#[inline(always)]
pub fn backward(l: &[f64], n: usize, x: &mut [f64]) {
    for i in (0..n).rev() {
        let mut v = x[i];
        for k in i + 1..n {
            v -= l[k * n + i] * x[k];
        }
        x[i] = v * l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A x = b` for a positive and a negative definite matrix, checked by multiplying back.
    #[test]
    fn solves_definite_systems_of_either_sign() {
        let a = [4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0];
        for sign in [1.0, -1.0] {
            let a: Vec<f64> = a.iter().map(|v| sign * v).collect();
            let mut l = a.clone();
            let p = factor(&mut l, 3, sign, 1e-13).unwrap();
            assert!(p.min > 0.0 && p.max >= p.min && p.decay > 0.0 && p.decay <= 1.0);
            let b = [1.0, -2.0, 0.5];
            let mut x = b;
            solve(&l, 3, sign, &mut x);
            for i in 0..3 {
                let r: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
                // Round-off of a 3 × 3 solve with condition ≈ 3.
                assert!((r - b[i]).abs() < 1e-14, "sign {sign}, row {i}: {r} vs {}", b[i]);
            }
        }
    }

    /// The decay is unchanged by a diagonal scaling: `[[1, r], [r, 1]]` loses `1 − r²` of its second
    /// diagonal entry however its rows and columns are scaled.
    #[test]
    fn decay_ignores_diagonal_scaling() {
        let r = 0.999;
        for s in [1.0, 1e-4, 1e5] {
            let mut a = [1.0, r * s, r * s, s * s];
            let p = factor(&mut a, 2, 1.0, 1e-13).unwrap();
            assert!((p.decay - (1.0 - r * r)).abs() < 1e-12, "scale {s}: {}", p.decay);
        }
    }

    /// A singular matrix (rank 1) and a matrix of the wrong sign are refused.
    #[test]
    fn refuses_singular_and_indefinite() {
        let mut a = [1.0, 1.0, 1.0, 1.0];
        assert!(factor(&mut a, 2, 1.0, 1e-13).is_err());
        let mut b = [1.0, 0.0, 0.0, 2.0];
        assert!(factor(&mut b, 2, -1.0, 1e-13).is_err());
        let mut c = [f64::NAN, 0.0, 0.0, 1.0];
        assert!(factor(&mut c, 2, 1.0, 1e-13).is_err());
    }
}
