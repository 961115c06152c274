//! Row operations on row-major blocks of right-hand sides with per-row column ranges, shared by
//! the LU solves that work by rows ([`super::SparseLu::solve_rows`], [`super::SmallLu::solve_rows`]).

/// Row `i` of a row-major matrix (`width` columns) `+= alpha ×` row `j`, over columns `lo..hi`.
#[inline]
pub(crate) fn row_axpy(y: &mut [f64], width: usize, i: usize, j: usize, alpha: f64, lo: usize, hi: usize) {
    let (dst, src) = if i < j {
        let (a, b) = y.split_at_mut(j * width);
        (&mut a[i * width..(i + 1) * width], &b[..width])
    } else {
        let (a, b) = y.split_at_mut(i * width);
        (&mut b[..width], &a[j * width..(j + 1) * width])
    };
    for (d, s) in dst[lo..hi].iter_mut().zip(&src[lo..hi]) {
        *d += alpha * s;
    }
}

/// The smallest range holding both (empty ranges are `lo ≥ hi`).
#[inline]
pub(crate) fn union(a: (usize, usize), b: (usize, usize)) -> (usize, usize) {
    match (a.0 < a.1, b.0 < b.1) {
        (false, _) => b,
        (_, false) => a,
        _ => (a.0.min(b.0), a.1.max(b.1)),
    }
}
