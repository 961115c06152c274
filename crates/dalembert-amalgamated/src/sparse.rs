//! Sparse factorization of the amalgamated system for larger models: the pattern (mass blocks, the
//! two identities, and `B_i` — the identity on the independent rows and a full block on the
//! dependent ones) depends only on the partition, so its symbolic LU ([`SparseLu`]) is computed once
//! per partition and reused until the next re-partition.

use dalembert_system::linalg::SparseLu;
use dalembert_system::{BlockDiagonal, Partition};
use faer::Mat;

pub(crate) struct SparseSystem {
    /// The independent coordinates this pattern was built for.
    pub independent: Vec<usize>,
    lu: SparseLu,
    /// Value positions of the mass-block entries (in `BlockDiagonal::entries` order).
    mass_pos: Vec<usize>,
    /// Value positions of the −I entries `(i, n+i)` and `(n+i, i)`.
    identity_pos: Vec<(usize, usize)>,
    /// `(row i, column j, position of (n+i, 2n+j), position of (2n+j, n+i))` for every `B_i` entry kept.
    b_pos: Vec<(usize, usize, usize, usize)>,
}

impl SparseSystem {
    pub fn new(mass: &BlockDiagonal, partition: &Partition) -> Option<Self> {
        let n = mass.dim();
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        let mut b_entries = Vec::new();
        for &d in &partition.dependent {
            for j in 0..ni {
                b_entries.push((d, j));
            }
        }
        for (j, &c) in partition.independent.iter().enumerate() {
            b_entries.push((c, j));
        }
        let entries = mass
            .entries()
            .map(|(r, c, _)| (r, c))
            .chain((0..n).flat_map(|i| [(i, n + i), (n + i, i)]))
            .chain(
                b_entries
                    .iter()
                    .flat_map(|&(i, j)| [(n + i, 2 * n + j), (2 * n + j, n + i)]),
            );
        let lu = SparseLu::new(dim, entries).ok()?;
        let mass_pos = mass.entries().map(|(r, c, _)| lu.position(r, c)).collect();
        let identity_pos = (0..n).map(|i| (lu.position(i, n + i), lu.position(n + i, i))).collect();
        let b_pos = b_entries
            .iter()
            .map(|&(i, j)| (i, j, lu.position(n + i, 2 * n + j), lu.position(2 * n + j, n + i)))
            .collect();
        Some(SparseSystem {
            independent: partition.independent.clone(),
            lu,
            mass_pos,
            identity_pos,
            b_pos,
        })
    }

    /// Fills the values for `M` and `B_i`, factors, and solves `K x = rhs` in place. `None` if the
    /// factorization fails.
    pub fn solve(&mut self, mass: &BlockDiagonal, b: &Mat<f64>, x: &mut [f64]) -> Option<()> {
        let values = self.lu.values_mut();
        values.iter_mut().for_each(|v| *v = 0.0);
        for (&p, (_, _, v)) in self.mass_pos.iter().zip(mass.entries()) {
            values[p] += v;
        }
        for &(p, pt) in &self.identity_pos {
            values[p] = -1.0;
            values[pt] = -1.0;
        }
        for &(i, j, p, pt) in &self.b_pos {
            values[p] = b[(i, j)];
            values[pt] = b[(i, j)];
        }
        self.lu.factor().ok()?;
        self.lu.solve_in_place(x);
        Some(())
    }
}
