//! Block-diagonal symmetric matrices with square blocks of any size (the system mass matrix, its
//! inverse, weights of minimum-norm steps).
//!
//! Blocks are stored row by row, one after the other; block `i` covers rows and columns
//! `offset(i) .. offset(i) + size(i)`. Products and the per-block Cholesky factorization allocate
//! nothing.

/// A block-diagonal matrix with square blocks.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BlockDiagonal {
    offsets: Vec<usize>,
    sizes: Vec<usize>,
    starts: Vec<usize>,
    values: Vec<f64>,
    dim: usize,
}

/// The largest block [`BlockDiagonal::invert_blocks`] handles (a spatial body with Euler
/// parameters as velocities has seven coordinates).
pub const MAX_BLOCK: usize = 8;

impl BlockDiagonal {
    /// Zero blocks of the given sizes, in order.
    pub fn zeros(sizes: impl IntoIterator<Item = usize>) -> Self {
        let mut m = BlockDiagonal::default();
        for s in sizes {
            m.offsets.push(m.dim);
            m.sizes.push(s);
            m.starts.push(m.values.len());
            m.dim += s;
            m.values.extend(std::iter::repeat_n(0.0, s * s));
        }
        m
    }

    /// The matrix dimension.
    #[inline]
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of blocks.
    #[inline]
    pub fn num_blocks(&self) -> usize {
        self.sizes.len()
    }

    /// First row (and column) of block `i`.
    #[inline]
    pub fn offset(&self, i: usize) -> usize {
        self.offsets[i]
    }

    /// Size of block `i`.
    #[inline]
    pub fn size(&self, i: usize) -> usize {
        self.sizes[i]
    }

    /// Block `i`, row by row (`size × size` entries).
    #[inline]
    pub fn block(&self, i: usize) -> &[f64] {
        let s = self.sizes[i];
        &self.values[self.starts[i]..self.starts[i] + s * s]
    }

    /// Block `i`, row by row, for writing.
    #[inline]
    pub fn block_mut(&mut self, i: usize) -> &mut [f64] {
        let s = self.sizes[i];
        &mut self.values[self.starts[i]..self.starts[i] + s * s]
    }

    /// Entry `(r, c)` of block `i` (local indices).
    #[inline]
    pub fn get(&self, i: usize, r: usize, c: usize) -> f64 {
        self.values[self.starts[i] + r * self.sizes[i] + c]
    }

    /// Every stored entry as `(row, column, value)` in global indices, block by block, row by row.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.num_blocks()).flat_map(move |i| {
            let (o, s) = (self.offsets[i], self.sizes[i]);
            self.block(i)
                .iter()
                .enumerate()
                .map(move |(k, &v)| (o + k / s, o + k % s, v))
        })
    }

    /// `y ← y + α A x`. Blocks of 3 and 6 (planar and spatial bodies) take an unrolled kernel.
    pub fn mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        for i in 0..self.num_blocks() {
            let (o, s) = (self.offsets[i], self.sizes[i]);
            let b = self.block(i);
            match s {
                3 => block_mul_add::<3>(alpha, b, &x[o..o + 3], &mut y[o..o + 3]),
                6 => block_mul_add::<6>(alpha, b, &x[o..o + 6], &mut y[o..o + 6]),
                _ => {
                    for r in 0..s {
                        let row = &b[r * s..(r + 1) * s];
                        let dot: f64 = row.iter().zip(&x[o..o + s]).map(|(a, v)| a * v).sum();
                        y[o + r] += alpha * dot;
                    }
                }
            }
        }
    }

    /// `y ← A_i x` for block `i` alone (`x`, `y` of the block's size).
    #[inline]
    pub fn block_mul(&self, i: usize, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        let b = self.block(i);
        match self.sizes[i] {
            3 => block_mul_add::<3>(1.0, b, x, y),
            6 => block_mul_add::<6>(1.0, b, x, y),
            s => {
                for r in 0..s {
                    y[r] = b[r * s..(r + 1) * s].iter().zip(x).map(|(a, v)| a * v).sum();
                }
            }
        }
    }

    /// Largest entry magnitude.
    pub fn max_abs(&self) -> f64 {
        self.values.iter().fold(0.0, |a, v| a.max(v.abs()))
    }

    /// Global indices of the zero diagonal entries (coordinates without inertia).
    pub fn zero_diagonal(&self) -> Vec<usize> {
        self.entries()
            .filter(|&(r, c, v)| r == c && v == 0.0)
            .map(|(r, _, _)| r)
            .collect()
    }

    /// Writes the inverse of every block of `self` into the same-shaped `out`, by Cholesky. Fails
    /// with the index of the first block that is not positive definite (relative pivot below
    /// `1e-14`) or larger than [`MAX_BLOCK`]. Allocates nothing.
    pub fn invert_blocks(&self, out: &mut BlockDiagonal) -> Result<(), usize> {
        for i in 0..self.num_blocks() {
            if !self.invert_block(i, out.block_mut(i)) {
                return Err(i);
            }
        }
        Ok(())
    }

    /// Writes the inverse of block `i` (row by row) into `inv` by Cholesky; `false` when the block
    /// is not positive definite (relative pivot below `1e-14`) or larger than [`MAX_BLOCK`].
    pub fn invert_block(&self, i: usize, inv: &mut [f64]) -> bool {
        let s = self.sizes[i];
        if s > MAX_BLOCK {
            return false;
        }
        let a = self.block(i);
        let scale = (0..s).map(|k| a[k * s + k].abs()).fold(0.0, f64::max);
        // L Lᵀ = A (lower triangle in l), then the columns of A⁻¹ from L Lᵀ x = e_k.
        let mut l = [0.0; MAX_BLOCK * MAX_BLOCK];
        for c in 0..s {
            for r in c..s {
                let mut v = a[r * s + c];
                for k in 0..c {
                    v -= l[r * MAX_BLOCK + k] * l[c * MAX_BLOCK + k];
                }
                if r == c {
                    // Also catches NaN: a non-finite block is not positive definite.
                    if v.is_nan() || v <= 1e-14 * scale {
                        return false;
                    }
                    l[c * MAX_BLOCK + c] = v.sqrt();
                } else {
                    l[r * MAX_BLOCK + c] = v / l[c * MAX_BLOCK + c];
                }
            }
        }
        for k in 0..s {
            let mut x = [0.0; MAX_BLOCK];
            x[k] = 1.0;
            for r in 0..s {
                let mut v = x[r];
                for j in 0..r {
                    v -= l[r * MAX_BLOCK + j] * x[j];
                }
                x[r] = v / l[r * MAX_BLOCK + r];
            }
            for r in (0..s).rev() {
                let mut v = x[r];
                for j in r + 1..s {
                    v -= l[j * MAX_BLOCK + r] * x[j];
                }
                x[r] = v / l[r * MAX_BLOCK + r];
            }
            for r in 0..s {
                inv[r * s + k] = x[r];
            }
        }
        true
    }

    /// True when block `i` is diagonal.
    pub fn block_is_diagonal(&self, i: usize) -> bool {
        let s = self.sizes[i];
        self.block(i)
            .iter()
            .enumerate()
            .all(|(k, &v)| k / s == k % s || v == 0.0)
    }
}

/// `y ← y + α B x` for one `N × N` block stored row by row (sizes known at compile time).
#[inline(always)]
fn block_mul_add<const N: usize>(alpha: f64, b: &[f64], x: &[f64], y: &mut [f64]) {
    let (b, x, y) = (&b[..N * N], &x[..N], &mut y[..N]);
    for r in 0..N {
        let mut dot = 0.0;
        for c in 0..N {
            dot += b[r * N + c] * x[c];
        }
        y[r] += alpha * dot;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A A⁻¹ = I` for blocks of sizes 1, 3 and 6 (a symmetric positive definite block built as
    /// `Bᵀ B + I`), to round-off; a block with a zero pivot is named.
    #[test]
    fn block_inverse_is_the_inverse() {
        let mut a = BlockDiagonal::zeros([1, 3, 6]);
        a.block_mut(0)[0] = 2.5;
        for (i, s) in [(1usize, 3usize), (2, 6)] {
            let b: Vec<f64> = (0..s * s).map(|k| ((k * 7 + 3) % 11) as f64 / 5.0 - 1.0).collect();
            let blk = a.block_mut(i);
            for r in 0..s {
                for c in 0..s {
                    blk[r * s + c] = (0..s).map(|k| b[k * s + r] * b[k * s + c]).sum::<f64>() + f64::from(r == c);
                }
            }
        }
        let mut inv = a.clone();
        a.invert_blocks(&mut inv).unwrap();
        for col in 0..a.dim() {
            let e: Vec<f64> = (0..a.dim()).map(|k| f64::from(k == col)).collect();
            let mut x = vec![0.0; a.dim()];
            inv.mul_add(1.0, &e, &mut x);
            let mut back = vec![0.0; a.dim()];
            a.mul_add(1.0, &x, &mut back);
            for (k, v) in back.iter().enumerate() {
                assert!((v - e[k]).abs() < 1e-13, "column {col}, row {k}: {v}");
            }
        }
        a.block_mut(1)[4] = 0.0;
        a.block_mut(1)[1] = 0.0;
        a.block_mut(1)[3] = 0.0;
        a.block_mut(1)[5] = 0.0;
        a.block_mut(1)[7] = 0.0;
        assert_eq!(a.invert_blocks(&mut inv), Err(1));
    }
}
