//! Square-root-free Cholesky `A = L D Lᵀ` (unit lower `L`, diagonal `D`) of a small symmetric
//! definite matrix stored row by row, in place: the blocks of the tree factorization and its loop
//! closure. Allocates nothing.
//!
//! `sign` states the expected definiteness: `+1` positive definite (every `d_k > 0`), `−1` negative
//! definite (every `d_k < 0`, the multiplier blocks of a saddle-point matrix). The diagonal of the
//! factored storage holds `1 / d_k`, so that solves multiply: one division per pivot and no square
//! root, where the latency of a square root and a division per pivot dominated the chain's
//! strictly sequential elimination (perf, planar chain of 16).

/// The pivots of a factorization by [`factor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pivots {
    /// Smallest `|d_k|`.
    pub min: f64,
    /// Largest `|d_k|`.
    pub max: f64,
    /// Smallest `d_k / a_kk`: how much of each diagonal entry survived elimination, a measure of
    /// near-singularity unchanged by a diagonal scaling of `A` (`1` for a diagonal matrix; its
    /// inverse is a lower bound of the condition number of the equilibrated `A`).
    pub decay: f64,
}

/// Factors `A` (`n × n`, row-major, lower triangle and diagonal read) into unit `L` (strict lower
/// triangle) and `1 / d_k` (diagonal); the strict upper triangle is used as workspace.
///
/// Fails with the offending pivot `d` when `sign · d ≤ tolerance · max_k sign · a_kk` (or NaN): `A`
/// is not definite of that sign to that relative tolerance.
#[inline(always)]
pub fn factor(a: &mut [f64], n: usize, sign: f64, tolerance: f64) -> Result<Pivots, f64> {
    let a = &mut a[..n * n];
    let mut largest = 0.0f64;
    for i in 0..n {
        largest = largest.max(sign * a[i * n + i]);
    }
    let (mut dmin, mut dmax, mut decay) = (f64::INFINITY, 0.0f64, 1.0f64);
    for j in 0..n {
        // U_jk = L_jk d_k, kept in the upper triangle at (k, j) while row j is formed.
        let mut d = a[j * n + j];
        let diagonal = d;
        for k in 0..j {
            let mut u = a[j * n + k];
            for q in 0..k {
                u -= a[q * n + j] * a[k * n + q];
            }
            a[k * n + j] = u;
            let l = u * a[k * n + k];
            a[j * n + k] = l;
            d -= u * l;
        }
        let s = sign * d;
        if s.is_nan() || s <= tolerance * largest {
            return Err(d);
        }
        decay = decay.min(d / diagonal);
        dmin = dmin.min(s);
        dmax = dmax.max(s);
        a[j * n + j] = 1.0 / d;
    }
    Ok(Pivots {
        min: dmin,
        max: dmax,
        decay,
    })
}

/// `x ← A⁻¹ x` with the factor of [`factor`].
#[inline(always)]
pub fn solve(f: &[f64], n: usize, x: &mut [f64]) {
    forward(f, n, x);
    for i in 0..n {
        x[i] *= f[i * n + i];
    }
    backward(f, n, x);
}

/// `x ← L⁻¹ x` (unit forward substitution).
#[inline(always)]
pub fn forward(f: &[f64], n: usize, x: &mut [f64]) {
    for i in 1..n {
        let mut v = x[i];
        for (a, b) in f[i * n..i * n + i].iter().zip(&x[..i]) {
            v -= a * b;
        }
        x[i] = v;
    }
}

/// `x ← L⁻ᵀ x` (unit back substitution).
#[inline(always)]
pub fn backward(f: &[f64], n: usize, x: &mut [f64]) {
    for i in (0..n.saturating_sub(1)).rev() {
        let mut v = x[i];
        for k in i + 1..n {
            v -= f[k * n + i] * x[k];
        }
        x[i] = v;
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
            let mut f = a.clone();
            let p = factor(&mut f, 3, sign, 1e-13).unwrap();
            assert!(p.min > 0.0 && p.max >= p.min && p.decay > 0.0 && p.decay <= 1.0);
            let b = [1.0, -2.0, 0.5];
            let mut x = b;
            solve(&f, 3, &mut x);
            for i in 0..3 {
                let r: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
                // Round-off of a 3 × 3 solve with condition ≈ 3.
                assert!((r - b[i]).abs() < 1e-14, "sign {sign}, row {i}: {r} vs {}", b[i]);
            }
        }
    }

    /// A 6 × 6 positive definite matrix (`B Bᵀ + I` for a fixed `B`): the solve of `A x = A e`
    /// returns `e` to round-off (condition below 1e3).
    #[test]
    fn recovers_a_known_solution_of_a_six_by_six() {
        let n = 6;
        let bm: Vec<f64> = (0..n * n).map(|k| ((k * 7 % 11) as f64 - 5.0) / 5.0).collect();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n).map(|k| bm[i * n + k] * bm[j * n + k]).sum::<f64>() + f64::from(u8::from(i == j));
            }
        }
        let e: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
        let mut x: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a[i * n + j] * e[j]).sum()).collect();
        let mut f = a.clone();
        factor(&mut f, n, 1.0, 1e-13).unwrap();
        solve(&f, n, &mut x);
        for i in 0..n {
            assert!((x[i] - e[i]).abs() < 1e-12, "{i}: {} vs {}", x[i], e[i]);
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

    /// A singular matrix (rank 1), a matrix of the wrong sign and NaN are refused.
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
