//! Sparse factorization of the amalgamated system for larger models: the pattern (mass blocks, the
//! two identities, and `B_i` — the identity on the independent rows and a full block on the
//! dependent ones) depends only on the partition, so its symbolic LU is computed once per partition
//! and reused until the next re-partition.

use dalembert_constraints::sparse_pattern::{compress_columns, entry_position};
use dalembert_constraints::Partition;
use dalembert_kinematics::MassMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, Par};

pub(crate) struct SparseSystem {
    /// The independent coordinates this pattern was built for.
    pub independent: Vec<usize>,
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// Value positions of the mass-block entries (9 per body).
    mass_pos: Vec<usize>,
    /// Value positions of the −I entries `(i, n+i)` and `(n+i, i)`.
    identity_pos: Vec<(usize, usize)>,
    /// `(row i, column j, position of (n+i, 2n+j), position of (2n+j, n+i))` for every `B_i` entry kept.
    b_pos: Vec<(usize, usize, usize, usize)>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
}

impl SparseSystem {
    pub fn new(n: usize, partition: &Partition) -> Option<Self> {
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); dim];
        let mut entries = Vec::new();
        for b in 0..n / 3 {
            for k in 0..9 {
                entries.push((3 * b + k / 3, 3 * b + k % 3));
            }
        }
        for i in 0..n {
            entries.push((i, n + i));
            entries.push((n + i, i));
        }
        let mut b_entries = Vec::new();
        for &d in &partition.dependent {
            for j in 0..ni {
                b_entries.push((d, j));
            }
        }
        for (j, &c) in partition.independent.iter().enumerate() {
            b_entries.push((c, j));
        }
        for &(i, j) in &b_entries {
            entries.push((n + i, 2 * n + j));
            entries.push((2 * n + j, n + i));
        }
        for &(r, c) in &entries {
            cols[c].push(r);
        }
        let (col_ptr, row_idx) = compress_columns(cols);
        let pos = |r: usize, c: usize| entry_position(&col_ptr, &row_idx, r, c);
        let mass_pos = (0..n / 3)
            .flat_map(|b| (0..9).map(move |k| (3 * b + k / 3, 3 * b + k % 3)))
            .map(|(r, c)| pos(r, c))
            .collect();
        let identity_pos = (0..n).map(|i| (pos(i, n + i), pos(n + i, i))).collect();
        let b_pos = b_entries
            .iter()
            .map(|&(i, j)| (i, j, pos(n + i, 2 * n + j), pos(2 * n + j, n + i)))
            .collect();
        let symbolic = {
            let s = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            factorize_symbolic_lu(s, Default::default()).ok()?
        };
        let factor_buf = MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()));
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Some(SparseSystem {
            independent: partition.independent.clone(),
            dim,
            values: vec![0.0; row_idx.len()],
            col_ptr,
            row_idx,
            mass_pos,
            identity_pos,
            b_pos,
            symbolic,
            numeric: NumericLu::new(),
            factor_buf,
            solve_buf,
        })
    }

    /// Fills the values for `M` and `B_i`, factors, and solves `K x = rhs` in place. `None` if the
    /// factorization fails.
    pub fn solve(&mut self, mass: &MassMatrix, b: &Mat<f64>, x: &mut [f64]) -> Option<()> {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (blk_i, blk) in mass.blocks().iter().enumerate() {
            for k in 0..9 {
                self.values[self.mass_pos[9 * blk_i + k]] += blk[(k / 3, k % 3)];
            }
        }
        for &(p, pt) in &self.identity_pos {
            self.values[p] = -1.0;
            self.values[pt] = -1.0;
        }
        for &(i, j, p, pt) in &self.b_pos {
            self.values[p] = b[(i, j)];
            self.values[pt] = b[(i, j)];
        }
        let s = SymbolicSparseColMatRef::new_checked(self.dim, self.dim, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(s, &self.values);
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.factor_buf),
                Default::default(),
            )
            .ok()?;
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, self.dim, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
        Some(())
    }

    /// `y = K x` with the current values.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.dim {
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                y[self.row_idx[k]] += self.values[k] * x[c];
            }
        }
    }
}
