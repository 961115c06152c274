//! The choice of a partition by LU with full pivoting, in storage sized once: a tracker keeps one
//! ([`super::PartitionTracker`]), so that a re-partition while stepping allocates nothing.

use super::Partition;
use crate::{ConstraintSet, ConstraintValues};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::full_pivoting::factor::{lu_in_place, lu_in_place_scratch};
use faer::{Mat, MatMut, Par};

/// Largest `m × n` Jacobian whose choice storage a tracker keeps (8 MB of values): above it each
/// re-partition allocates its dense matrices for the time of the choice.
pub const KEPT_UP_TO: usize = 1 << 20;

/// Storage of one partition choice for an `m × n` Jacobian: `C_qᵀ`, the selected rows, the
/// permutations and the LU's scratch.
pub struct PartitionChoice {
    jt: Mat<f64>,
    sel: Mat<f64>,
    row_perm: Vec<usize>,
    row_perm_inv: Vec<usize>,
    col_perm: Vec<usize>,
    col_perm_inv: Vec<usize>,
    /// For each equation, its place among the chosen rows (`usize::MAX`: not chosen).
    row_slot: Vec<usize>,
    buf: MemBuffer,
}

impl std::fmt::Debug for PartitionChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PartitionChoice")
            .field("equations", &self.jt.ncols())
            .field("coordinates", &self.jt.nrows())
            .finish()
    }
}

/// Numerical rank and pivot order of the columns of `a` (full-pivot LU in place, `a` overwritten):
/// the first `rank` entries of the order (in `col_perm`) are independent columns.
fn rank_in_place(
    a: MatMut<'_, f64>,
    rank_tolerance: f64,
    perms: (&mut [usize], &mut [usize], &mut [usize], &mut [usize]),
    stack: &mut MemStack,
) -> usize {
    let (m, n) = a.shape();
    let (row_perm, row_perm_inv, col_perm, col_perm_inv) = perms;
    if m == 0 || n == 0 {
        col_perm.iter_mut().enumerate().for_each(|(k, c)| *c = k);
        return 0;
    }
    let (mut a, k) = (a, m.min(n));
    lu_in_place(
        a.as_mut(),
        &mut row_perm[..m],
        &mut row_perm_inv[..m],
        &mut col_perm[..n],
        &mut col_perm_inv[..n],
        Par::Seq,
        stack,
        Default::default(),
    );
    let largest = (0..k).map(|i| a[(i, i)].abs()).fold(0.0, f64::max);
    if largest == 0.0 || !largest.is_finite() {
        0
    } else {
        (0..k)
            .take_while(|&i| a[(i, i)].abs() > rank_tolerance * largest)
            .count()
    }
}

impl PartitionChoice {
    /// Storage for choosing partitions of an `m × n` Jacobian.
    pub fn new(m: usize, n: usize) -> Self {
        let k = m.max(n);
        let scratch =
            lu_in_place_scratch::<usize, f64>(n, m, Par::Seq, Default::default())
                .or(lu_in_place_scratch::<usize, f64>(m, n, Par::Seq, Default::default()));
        PartitionChoice {
            jt: Mat::zeros(n, m),
            sel: Mat::zeros(m, n),
            row_perm: vec![0; k],
            row_perm_inv: vec![0; k],
            col_perm: vec![0; k],
            col_perm_inv: vec![0; k],
            row_slot: vec![usize::MAX; m],
            buf: MemBuffer::new(scratch),
        }
    }

    /// Chooses the partition of `sys` at `values` into `out` (see
    /// [`Partition::choose_ranked`]), reusing `out`'s storage: allocates nothing once `out` has
    /// held a partition of this system.
    pub fn choose(
        &mut self,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
        rank_tolerance: f64,
        rank: Option<usize>,
        out: &mut Partition,
    ) {
        let (n, m) = (self.jt.nrows(), self.jt.ncols());
        // Independent rows: pivot columns of C_qᵀ.
        self.jt.fill(0.0);
        for (&(r, c), &v) in sys.pattern().entries().iter().zip(&values.jacobian) {
            self.jt[(c, r)] += v;
        }
        let found = rank_in_place(
            self.jt.as_mut(),
            rank_tolerance,
            (
                &mut self.row_perm,
                &mut self.row_perm_inv,
                &mut self.col_perm,
                &mut self.col_perm_inv,
            ),
            MemStack::new(&mut self.buf),
        );
        let rank = rank.map_or(found, |r| r.min(m));
        out.rows.clear();
        out.rows.extend_from_slice(&self.col_perm[..rank]);
        // Dependent coordinates: pivot columns of the selected rows.
        let mut sel = self.sel.as_mut().subrows_mut(0, rank);
        sel.fill(0.0);
        self.row_slot.iter_mut().for_each(|s| *s = usize::MAX);
        for (i, &r) in out.rows.iter().enumerate() {
            self.row_slot[r] = i;
        }
        for (&(r, c), &v) in sys.pattern().entries().iter().zip(&values.jacobian) {
            let i = self.row_slot[r];
            if i != usize::MAX {
                sel[(i, c)] += v;
            }
        }
        rank_in_place(
            sel,
            rank_tolerance,
            (
                &mut self.row_perm,
                &mut self.row_perm_inv,
                &mut self.col_perm,
                &mut self.col_perm_inv,
            ),
            MemStack::new(&mut self.buf),
        );
        out.dependent.clear();
        out.dependent.extend_from_slice(&self.col_perm[..rank]);
        out.independent.clear();
        out.independent.extend_from_slice(&self.col_perm[rank..n]);
        out.independent.sort_unstable();
    }
}
