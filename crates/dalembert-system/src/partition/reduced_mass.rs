//! The reduced mass matrix `M_i = B_iᵀ M B_i` of the embedding (and the Schur complement of the
//! amalgamated system), from the rows of `B_i` with their column ranges, block by block of `M`.
//!
//! For a block `b` of `M` (rows `o .. o + s`), with `W = M_b B_b`,
//! `B_bᵀ M_b B_b = Σ_a (row a of B_b)ᵀ (row a of W)`: the block's rows are compacted to their common
//! column range `lo..hi`, and every column `q` of `M_i`'s lower triangle in that range gets
//! `M_i[p, q] += Σ_a B[a, p] W[a, q]` (`p ≥ q`) in one pass for two or three rows at a time. A row
//! whose range is a single column `j` (an independent coordinate's row, `e_j`) only touches row `j`
//! of `M_i` and is added on its own.
//!
//! The kernel is compiled three times and picked at run time: for AVX-512, for AVX2 with fused
//! multiply-add, and for the baseline the binary targets (SSE2 on x86-64).

use crate::BlockDiagonal;
use faer::Mat;

/// The rows of `B_i` as [`super::VelocityTransform`] stores them.
pub(crate) struct BRows<'a> {
    /// `n × ni` row-major, rows in partition order.
    pub b: &'a [f64],
    pub ni: usize,
    /// Position of each coordinate's row in `b`.
    pub col_of: &'a [usize],
    /// Column range of each row of `b` (partition order).
    pub support: &'a [(usize, usize)],
}

impl BRows<'_> {
    #[inline(always)]
    fn range(&self, c: usize) -> (usize, usize) {
        self.support[self.col_of[c]]
    }

    #[inline(always)]
    fn row(&self, c: usize) -> &[f64] {
        let k = self.col_of[c];
        &self.b[k * self.ni..(k + 1) * self.ni]
    }
}

/// Writes the lower triangle of `B_iᵀ M B_i` into `out`; `bb`, `wb` are scratch of (largest block
/// size) × `ni` each, `long` scratch for the indices of one block's rows.
pub(crate) fn reduced_mass(
    rows: &BRows<'_>,
    mass: &BlockDiagonal,
    bb: &mut [f64],
    wb: &mut [f64],
    long: &mut Vec<usize>,
    out: &mut Mat<f64>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has the features the function is compiled for (checked just above).
            unsafe { kernel_avx512(rows, mass, bb, wb, long, out) };
            return;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: as above.
            unsafe { kernel_avx2(rows, mass, bb, wb, long, out) };
            return;
        }
    }
    kernel::<false>(rows, mass, bb, wb, long, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn kernel_avx512(
    rows: &BRows<'_>,
    mass: &BlockDiagonal,
    bb: &mut [f64],
    wb: &mut [f64],
    long: &mut Vec<usize>,
    out: &mut Mat<f64>,
) {
    kernel::<true>(rows, mass, bb, wb, long, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn kernel_avx2(
    rows: &BRows<'_>,
    mass: &BlockDiagonal,
    bb: &mut [f64],
    wb: &mut [f64],
    long: &mut Vec<usize>,
    out: &mut Mat<f64>,
) {
    kernel::<true>(rows, mass, bb, wb, long, out);
}

/// `a b + c`, fused (one rounding) where the CPU has the instruction, else plain.
#[inline(always)]
fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

#[inline(always)]
fn kernel<const FMA: bool>(
    rows: &BRows<'_>,
    mass: &BlockDiagonal,
    bb: &mut [f64],
    wb: &mut [f64],
    long: &mut Vec<usize>,
    out: &mut Mat<f64>,
) {
    let ni = rows.ni;
    for q in 0..ni {
        out.col_as_slice_mut(q)[q..].iter_mut().for_each(|v| *v = 0.0);
    }
    for blk in 0..mass.num_blocks() {
        let (o, s) = (mass.offset(blk), mass.size(blk));
        let block = mass.block(blk);
        let (mut lo, mut hi) = (ni, 0);
        for c in o..o + s {
            let (l, h) = rows.range(c);
            if l < h {
                lo = lo.min(l);
                hi = hi.max(h);
            }
        }
        if lo >= hi {
            continue;
        }
        let len = hi - lo;
        let (bb, wb) = (&mut bb[..s * len], &mut wb[..s * len]);
        bb.iter_mut().for_each(|v| *v = 0.0);
        wb.iter_mut().for_each(|v| *v = 0.0);
        long.clear();
        for a in 0..s {
            let (l, h) = rows.range(o + a);
            if l < h {
                bb[a * len + l - lo..a * len + h - lo].copy_from_slice(&rows.row(o + a)[l..h]);
            }
            if h > l + 1 {
                // Allocates only for a block with more long rows than any before.
                long.push(a);
            }
        }
        for a in 0..s {
            for c in 0..s {
                let m = block[a * s + c];
                if m != 0.0 {
                    let (w, src) = (&mut wb[a * len..(a + 1) * len], &bb[c * len..(c + 1) * len]);
                    for (w, x) in w.iter_mut().zip(src) {
                        *w = madd::<FMA>(m, *x, *w);
                    }
                }
            }
        }
        // Rows whose range is one column j: M_i[j, q] += B[a, j] W[a, q] for q ≤ j.
        for a in 0..s {
            let (l, h) = rows.range(o + a);
            if h == l + 1 {
                let bj = rows.row(o + a)[l];
                for q in lo..=l {
                    let v = &mut out[(l, q)];
                    *v = madd::<FMA>(bj, wb[a * len + q - lo], *v);
                }
            }
        }
        // The other rows, up to three per pass over a column of M_i.
        for q in 0..len {
            let col = &mut out.col_as_slice_mut(lo + q)[lo + q..hi];
            let k = col.len();
            let row = |a: usize| &bb[a * len + q..a * len + q + k];
            let w = |a: usize| wb[a * len + q];
            let n_long = long.len();
            let mut i = 0;
            while i < n_long {
                match n_long - i {
                    1 => {
                        let (a0,) = (long[i],);
                        let w0 = w(a0);
                        for (m, x0) in col.iter_mut().zip(row(a0)) {
                            *m = madd::<FMA>(w0, *x0, *m);
                        }
                        i += 1;
                    }
                    2 => {
                        let (a0, a1) = (long[i], long[i + 1]);
                        let (w0, w1) = (w(a0), w(a1));
                        for ((m, x0), x1) in col.iter_mut().zip(row(a0)).zip(row(a1)) {
                            *m = madd::<FMA>(w1, *x1, madd::<FMA>(w0, *x0, *m));
                        }
                        i += 2;
                    }
                    _ => {
                        let (a0, a1, a2) = (long[i], long[i + 1], long[i + 2]);
                        let (w0, w1, w2) = (w(a0), w(a1), w(a2));
                        for (((m, x0), x1), x2) in col.iter_mut().zip(row(a0)).zip(row(a1)).zip(row(a2)) {
                            *m = madd::<FMA>(w2, *x2, madd::<FMA>(w1, *x1, madd::<FMA>(w0, *x0, *m)));
                        }
                        i += 3;
                    }
                }
            }
        }
    }
}
