//! The choice of a partition by LU with full pivoting, in storage sized once: a tracker keeps one
//! ([`super::PartitionTracker`]), so that a re-partition while stepping allocates nothing.

use super::Partition;
use crate::linalg::FullPivot;
use crate::{ConstraintSet, ConstraintValues};
use faer::Mat;

/// Largest `m × n` Jacobian whose choice storage a tracker keeps (8 MB of values): above it each
/// re-partition allocates its dense matrices for the time of the choice.
pub const KEPT_UP_TO: usize = 1 << 20;

/// Storage of one partition choice for an `m × n` Jacobian: `C_qᵀ`, the selected rows, and the
/// full-pivot LU's permutations and scratch.
pub struct PartitionChoice {
    jt: Mat<f64>,
    sel: Mat<f64>,
    pivot: FullPivot,
    /// For each equation, its place among the chosen rows (`usize::MAX`: not chosen).
    row_slot: Vec<usize>,
}

impl std::fmt::Debug for PartitionChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PartitionChoice")
            .field("equations", &self.jt.ncols())
            .field("coordinates", &self.jt.nrows())
            .finish()
    }
}

impl PartitionChoice {
    /// Storage for choosing partitions of an `m × n` Jacobian.
    pub fn new(m: usize, n: usize) -> Self {
        PartitionChoice {
            jt: Mat::zeros(n, m),
            sel: Mat::zeros(m, n),
            pivot: FullPivot::new(m, n),
            row_slot: vec![usize::MAX; m],
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
        sys.jacobian_dense_into(values, self.jt.as_mut().transpose_mut());
        let found = self.pivot.rank(self.jt.as_mut(), rank_tolerance);
        let rank = rank.map_or(found, |r| r.min(m));
        out.rows.clear();
        out.rows.extend_from_slice(&self.pivot.order(m)[..rank]);
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
        self.pivot.rank(sel, rank_tolerance);
        out.dependent.clear();
        out.dependent.extend_from_slice(&self.pivot.order(n)[..rank]);
        out.independent.clear();
        out.independent.extend_from_slice(&self.pivot.order(n)[rank..]);
        out.independent.sort_unstable();
    }
}
