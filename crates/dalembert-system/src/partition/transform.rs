//! The velocity transformation `B_i`, `γ_i` at one state (`docs/equations.md` §4), computed with the
//! sparsity of the constraints:
//!
//! * `C_qd` is factored by an unblocked dense LU up to [`DENSE_LIMIT`] dependent coordinates and by
//!   faer's sparse LU above (pattern and column order computed once per partition);
//! * `B_i` is stored by rows, each with the range of columns outside which it is zero, and its
//!   dependent rows `−C_qd⁻¹ C_qi` are solved for by rows (`solve_rows` of the LU), each elimination
//!   step running over the ranges only: on a chain, a link's coordinates depend only on the joints
//!   before it, so `B_i` is half empty;
//! * the products `B_i x`, `B_iᵀ f` and the reduced mass matrix `B_iᵀ M B_i` run over those ranges
//!   only, block by block of `M`.
//!
//! Exact zeros are skipped, so every product equals the dense one to the last bit of the terms
//! kept; nothing allocates after the first evaluation of a partition.

use super::reduced_mass::{self, BRows};
use super::Partition;
use crate::blocks::MAX_BLOCK;
use crate::linalg::{SmallLu, SparseLu};
use crate::{BlockDiagonal, ConstraintSet, ConstraintValues};
use faer::Mat;

/// Up to this many dependent coordinates `C_qd` is factored dense (unblocked LU with partial
/// pivoting); above it, by sparse LU.
pub const DENSE_LIMIT: usize = 40;

/// The slots of `partition`'s rows and columns (the independent ones in ascending order).
fn mark_slots(partition: &Partition, row_slot: &mut [Option<usize>], col_slot: &mut [Result<usize, usize>]) {
    row_slot.iter_mut().for_each(|s| *s = None);
    for (i, &row) in partition.rows.iter().enumerate() {
        row_slot[row] = Some(i);
    }
    for (k, &d) in partition.dependent.iter().enumerate() {
        col_slot[d] = Ok(k);
    }
    for (j, &c) in partition.independent.iter().enumerate() {
        col_slot[c] = Err(j);
    }
}

/// Where one entry of the constraint pattern goes.
#[derive(Debug, Clone, Copy)]
enum Slot {
    /// Into the factor's values (dense row-major position, or sparse value position).
    Dependent(usize),
    /// Into `−C_qi` at (row slot, independent index), stored by rows in the dependent rows of
    /// `B_i`.
    Independent(usize, usize),
    /// A row outside the partition's independent equations.
    Unused,
}

#[derive(Debug)]
enum Factor {
    Dense(SmallLu),
    Sparse(Box<SparseLu>),
}

/// `B_i`, `γ_i` and the factorization of `C_qd` at one state: a workspace refilled in place at
/// every state, and laid out again in place for a new partition where its factor is dense
/// ([`VelocityTransform::rebuild`]).
#[derive(Debug)]
pub struct VelocityTransform {
    /// `B_i` by rows, `n × (n − r)` row-major, its rows in partition order (the `r` dependent
    /// coordinates, then the independent ones): row `c` of `B_i` starts at `col_of[c]·(n − r)`.
    b: Vec<f64>,
    ni: usize,
    col_of: Vec<usize>,
    /// For each row of `B_i` (in partition order), the columns `lo..hi` outside which it is zero.
    support: Vec<(usize, usize)>,
    /// `γ_i`, length `n`.
    pub gamma: Vec<f64>,
    factor: Factor,
    /// Destination of every constraint-pattern entry.
    slots: Vec<Slot>,
    /// The partition's dependent coordinates and independent equations (copies: the transform is
    /// used with the partition it was built for).
    dependent: Vec<usize>,
    rows: Vec<usize>,
    /// For each equation its place among the partition's rows, for each coordinate its place
    /// among the dependent (`Ok`) or independent (`Err`) ones.
    row_slot: Vec<Option<usize>>,
    col_slot: Vec<Result<usize, usize>>,
    /// Scratch of length `r`; one mass block's rows of `B_i` and of `M_b B_b`, compacted to their
    /// common column range (`s × (n − r)` each for the largest block size `s` met), and the
    /// block's rows that span more than one column.
    g: Vec<f64>,
    bb: Vec<f64>,
    wb: Vec<f64>,
    long: Vec<usize>,
    /// Ratio largest / smallest pivot of `C_qd`'s LU: a cheap condition estimate.
    pub condition: f64,
}

impl VelocityTransform {
    /// A workspace for `partition` of the constraint set `sys`.
    pub fn new(partition: &Partition, sys: &(impl ConstraintSet + ?Sized)) -> Self {
        let (n, m) = (sys.num_coordinates(), sys.num_equations());
        let (r, ni) = (partition.rows.len(), partition.independent.len());
        let mut row_slot = vec![None; m];
        let mut col_slot = vec![Err(0); n];
        mark_slots(partition, &mut row_slot, &mut col_slot);
        let entries = sys.pattern().entries();
        let dependent_entries = || {
            entries
                .iter()
                .filter_map(|&(row, col)| match (row_slot[row], col_slot[col]) {
                    (Some(i), Ok(k)) => Some((i, k)),
                    _ => None,
                })
        };
        let factor = match (r > DENSE_LIMIT)
            .then(|| SparseLu::with_right_hand_sides(r, dependent_entries(), ni))
            .and_then(Result::ok)
        {
            Some(lu) => Factor::Sparse(Box::new(lu)),
            None => Factor::Dense(SmallLu::new(r)),
        };
        let mut vt = VelocityTransform {
            b: vec![0.0; n * ni],
            ni,
            col_of: vec![0; n],
            support: vec![(0, 0); n],
            gamma: vec![0.0; n],
            factor,
            slots: vec![Slot::Unused; entries.len()],
            dependent: partition.dependent.clone(),
            rows: partition.rows.clone(),
            row_slot,
            col_slot,
            g: vec![0.0; r],
            bb: vec![0.0; MAX_BLOCK * ni],
            wb: vec![0.0; MAX_BLOCK * ni],
            long: Vec::with_capacity(MAX_BLOCK),
            condition: f64::INFINITY,
        };
        vt.lay_out(entries);
        vt
    }

    /// Makes this workspace the one of `partition` in place, without allocating, when it can: a
    /// dense factor (up to [`DENSE_LIMIT`] dependent coordinates) of the same size, for the same
    /// system. `false` (nothing changed) otherwise: a sparse factor's symbolic analysis belongs
    /// to its partition's pattern, so a new partition needs [`VelocityTransform::new`].
    pub fn rebuild(&mut self, partition: &Partition, sys: &(impl ConstraintSet + ?Sized)) -> bool {
        let (r, ni) = (partition.rows.len(), partition.independent.len());
        let same_size = r == self.rows.len()
            && ni == self.ni
            && self.col_slot.len() == sys.num_coordinates()
            && self.row_slot.len() == sys.num_equations()
            && self.slots.len() == sys.pattern().entries().len();
        if !(same_size && matches!(self.factor, Factor::Dense(_))) {
            return false;
        }
        mark_slots(partition, &mut self.row_slot, &mut self.col_slot);
        self.dependent.clear();
        self.dependent.extend_from_slice(&partition.dependent);
        self.rows.clear();
        self.rows.extend_from_slice(&partition.rows);
        self.condition = f64::INFINITY;
        self.lay_out(sys.pattern().entries());
        true
    }

    /// Where each pattern entry goes, and the identity rows of `B_i`, from the slots of the
    /// partition's rows and columns.
    fn lay_out(&mut self, entries: &[(usize, usize)]) {
        let (r, ni) = (self.rows.len(), self.ni);
        for (slot, &(row, col)) in self.slots.iter_mut().zip(entries) {
            *slot = match (self.row_slot[row], self.col_slot[col]) {
                (Some(i), Ok(k)) => Slot::Dependent(match &self.factor {
                    Factor::Dense(_) => i * r + k,
                    Factor::Sparse(lu) => lu.position(i, k),
                }),
                (Some(i), Err(j)) => Slot::Independent(i, j),
                (None, _) => Slot::Unused,
            };
        }
        self.b.iter_mut().for_each(|v| *v = 0.0);
        for (k, &d) in self.dependent.iter().enumerate() {
            self.col_of[d] = k;
        }
        for (c, slot) in self.col_slot.iter().enumerate() {
            if let Err(j) = *slot {
                self.col_of[c] = r + j;
                self.b[(r + j) * ni + j] = 1.0;
                self.support[r + j] = (j, j + 1);
            }
        }
    }

    /// Whether `C_qd` is factored dense (then [`VelocityTransform::rebuild`] can lay out another
    /// partition of the same size in place).
    pub fn is_dense(&self) -> bool {
        matches!(self.factor, Factor::Dense(_))
    }

    /// Number of independent coordinates (columns of `B_i`).
    pub fn num_independent(&self) -> usize {
        self.ni
    }

    /// Fills and factors `C_qd` from `values` (and writes `−C_qi` where [`VelocityTransform::compute`]
    /// expects it: until then the products with `B_i` are not valid); sets
    /// [`VelocityTransform::condition`]. Returns `false` if `C_qd` is singular. Allocates nothing.
    pub fn refactor(&mut self, values: &ConstraintValues) -> bool {
        let (r, ni) = (self.rows.len(), self.ni);
        let dependent_rows = &mut self.b[..r * ni];
        dependent_rows.iter_mut().for_each(|v| *v = 0.0);
        let ranges = &mut self.support[..r];
        ranges.iter_mut().for_each(|g| *g = (0, 0));
        let factor_values: &mut [f64] = match &mut self.factor {
            Factor::Dense(lu) => &mut lu.a,
            Factor::Sparse(lu) => lu.values_mut(),
        };
        factor_values.iter_mut().for_each(|v| *v = 0.0);
        for (slot, &v) in self.slots.iter().zip(&values.jacobian) {
            match *slot {
                Slot::Dependent(p) => factor_values[p] += v,
                Slot::Independent(i, j) => {
                    dependent_rows[i * ni + j] -= v;
                    let (lo, hi) = ranges[i];
                    ranges[i] = if lo < hi {
                        (lo.min(j), hi.max(j + 1))
                    } else {
                        (j, j + 1)
                    };
                }
                Slot::Unused => {}
            }
        }
        let (small, big) = match &mut self.factor {
            Factor::Dense(lu) => lu.factor(),
            Factor::Sparse(lu) => match lu.factor() {
                Ok(()) => lu.pivot_range(),
                Err(_) => (0.0, f64::INFINITY),
            },
        };
        self.condition = if r == 0 { 1.0 } else { big / small };
        self.condition.is_finite()
    }

    /// Computes `B_i` and `γ_i` for the acceleration right-hand side `rhs` (length `m`: `Q_d`, or
    /// its Baumgarte-modified form) from the factorization of the last
    /// [`VelocityTransform::refactor`]. Allocates nothing.
    pub fn compute(&mut self, rhs: &[f64]) {
        let (r, ni) = (self.rows.len(), self.ni);
        // −C_qd⁻¹ C_qi (the dependent rows of B_i) from −C_qi and its rows' column ranges, both
        // written by the last refactor.
        let (rows, ranges) = (&mut self.b[..r * ni], &mut self.support[..r]);
        match &mut self.factor {
            Factor::Dense(lu) => lu.solve_rows(rows, ni, ranges),
            Factor::Sparse(lu) => lu.solve_rows(rows, ni, ranges),
        }
        for (g, &row) in self.g.iter_mut().zip(&self.rows) {
            *g = rhs[row];
        }
        let mut g = std::mem::take(&mut self.g);
        self.solve_dependent(&mut g);
        self.g = g;
        self.gamma.iter_mut().for_each(|v| *v = 0.0);
        for (k, &d) in self.dependent.iter().enumerate() {
            self.gamma[d] = self.g[k];
        }
    }

    /// The particular solution `γ` of `C_q x = rhs` that [`VelocityTransform::compute`] writes
    /// (zero on the independent coordinates, `C_qd⁻¹ rhs_R` on the dependent ones, `rhs` of
    /// length `m`) into `out` (length `n`), for another right-hand side: `B_i` and the transform's
    /// own `γ` are left as they are. Allocates nothing.
    pub fn particular(&mut self, rhs: &[f64], out: &mut [f64]) {
        for (g, &row) in self.g.iter_mut().zip(&self.rows) {
            *g = rhs[row];
        }
        let mut g = std::mem::take(&mut self.g);
        self.solve_dependent(&mut g);
        self.g = g;
        out.iter_mut().for_each(|v| *v = 0.0);
        for (k, &d) in self.dependent.iter().enumerate() {
            out[d] = self.g[k];
        }
    }

    /// Solves `C_qd x = y` (length `r`) in place.
    pub fn solve_dependent(&mut self, y: &mut [f64]) {
        match &mut self.factor {
            Factor::Dense(lu) => lu.solve(y),
            Factor::Sparse(lu) => lu.solve_in_place(y),
        }
    }

    /// Solves `C_qdᵀ x = y` (length `r`) in place.
    pub fn solve_dependent_transpose(&mut self, y: &mut [f64]) {
        match &mut self.factor {
            Factor::Dense(lu) => lu.solve_transpose(y),
            Factor::Sparse(lu) => lu.solve_transpose_in_place(y),
        }
    }

    /// Row `c` of `B_i` (length `n − r`).
    pub fn b_row(&self, c: usize) -> &[f64] {
        let k = self.col_of[c];
        &self.b[k * self.ni..(k + 1) * self.ni]
    }

    /// Columns `lo..hi` outside which row `c` of `B_i` is zero.
    fn range(&self, c: usize) -> (usize, usize) {
        self.support[self.col_of[c]]
    }

    /// Largest magnitude of an entry of `B_i`.
    pub fn max_abs(&self) -> f64 {
        // Four independent maxima so that the loop vectorizes; a NaN in `B_i` also makes the
        // solutions that use it NaN, which the formulations check.
        let mut largest = [0.0f64; 4];
        for (k, &(lo, hi)) in self.support.iter().enumerate() {
            let row = &self.b[k * self.ni + lo..k * self.ni + hi];
            let mut chunks = row.chunks_exact(4);
            for chunk in &mut chunks {
                for (m, v) in largest.iter_mut().zip(chunk) {
                    *m = m.max(v.abs());
                }
            }
            for v in chunks.remainder() {
                largest[0] = largest[0].max(v.abs());
            }
        }
        largest.into_iter().fold(0.0, f64::max)
    }

    /// `out ← out + B_i x` (`x` of length `n − r`, `out` of length `n`).
    pub fn mul_add(&self, x: &[f64], out: &mut [f64]) {
        for (c, o) in out.iter_mut().enumerate() {
            let (lo, hi) = self.range(c);
            let row = &self.b_row(c)[lo..hi];
            *o += row.iter().zip(&x[lo..hi]).map(|(b, x)| b * x).sum::<f64>();
        }
    }

    /// `out ← B_iᵀ f` (`f` of length `n`, `out` of length `n − r`).
    pub fn mul_transpose(&self, f: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for (c, &fc) in f.iter().enumerate() {
            let (lo, hi) = self.range(c);
            if fc == 0.0 {
                continue;
            }
            for (o, b) in out[lo..hi].iter_mut().zip(&self.b_row(c)[lo..hi]) {
                *o += fc * b;
            }
        }
    }

    /// The lower triangle of the reduced mass matrix `B_iᵀ M B_i` into `out` (`(n − r)²`; the
    /// strictly upper triangle is left as it was). Block by block of `M`: the block's rows of
    /// `B_i` are compacted to their common column range `lo..hi` (`B_b`, zero outside each row's
    /// own range), `W = M_b B_b`, and `M_i[p, q] += Σ_a B_b[a, p] W[a, q]` for `p ≥ q` in that range:
    /// one pass over each column of `M_i` per block.
    pub fn reduced_mass(&mut self, mass: &BlockDiagonal, out: &mut Mat<f64>) {
        let ni = self.ni;
        // Blocks larger than MAX_BLOCK (any size is allowed): scratch grown once, on first use.
        let largest = (0..mass.num_blocks()).map(|b| mass.size(b)).max().unwrap_or(0);
        if self.bb.len() < largest * ni {
            self.bb.resize(largest * ni, 0.0);
            self.wb.resize(largest * ni, 0.0);
        }
        let VelocityTransform {
            b,
            col_of,
            support,
            bb,
            wb,
            long,
            ..
        } = self;
        let rows = BRows { b, ni, col_of, support };
        reduced_mass::reduced_mass(&rows, mass, bb, wb, long, out);
    }
}
