//! The numerical rank and pivot order of a dense matrix's columns by LU with full pivoting, in
//! storage sized once: the structure analyses use it once ([`crate::structure::column_rank`]), a
//! partition tracker at every re-partition (`partition/choice.rs`).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::full_pivoting::factor::{lu_in_place, lu_in_place_scratch};
use faer::{MatMut, Par};

/// The permutations and scratch of a full-pivot LU of matrices up to `rows × cols` (or
/// `cols × rows`).
pub struct FullPivot {
    row_perm: Vec<usize>,
    row_perm_inv: Vec<usize>,
    col_perm: Vec<usize>,
    col_perm_inv: Vec<usize>,
    buf: MemBuffer,
}

impl std::fmt::Debug for FullPivot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FullPivot").field("size", &self.col_perm.len()).finish()
    }
}

impl FullPivot {
    /// Storage for matrices up to `rows × cols`, either way round.
    pub fn new(rows: usize, cols: usize) -> Self {
        let k = rows.max(cols);
        let scratch =
            lu_in_place_scratch::<usize, f64>(rows, cols, Par::Seq, Default::default()).or(lu_in_place_scratch::<
                usize,
                f64,
            >(
                cols,
                rows,
                Par::Seq,
                Default::default(),
            ));
        FullPivot {
            row_perm: vec![0; k],
            row_perm_inv: vec![0; k],
            col_perm: vec![0; k],
            col_perm_inv: vec![0; k],
            buf: MemBuffer::new(scratch),
        }
    }

    /// Factors `a` in place (overwritten) and returns its numerical rank: the pivots above
    /// `rank_tolerance ×` the largest. Then [`FullPivot::order`] holds its columns in pivot order,
    /// the first `rank` independent. Allocates nothing.
    pub fn rank(&mut self, mut a: MatMut<'_, f64>, rank_tolerance: f64) -> usize {
        let (m, n) = a.shape();
        if m == 0 || n == 0 {
            self.col_perm.iter_mut().enumerate().for_each(|(k, c)| *c = k);
            return 0;
        }
        lu_in_place(
            a.as_mut(),
            &mut self.row_perm[..m],
            &mut self.row_perm_inv[..m],
            &mut self.col_perm[..n],
            &mut self.col_perm_inv[..n],
            Par::Seq,
            MemStack::new(&mut self.buf),
            Default::default(),
        );
        let k = m.min(n);
        let largest = (0..k).map(|i| a[(i, i)].abs()).fold(0.0, f64::max);
        if largest == 0.0 || !largest.is_finite() {
            0
        } else {
            (0..k)
                .take_while(|&i| a[(i, i)].abs() > rank_tolerance * largest)
                .count()
        }
    }

    /// The pivot order of the `n` columns of the last [`FullPivot::rank`].
    pub fn order(&self, n: usize) -> &[usize] {
        &self.col_perm[..n]
    }
}
