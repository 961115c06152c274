//! Range-space (Schur complement) back end for a positive definite mass matrix:
//!
//! ```text
//! S = C_q M⁻¹ C_qᵀ,   λ = S⁻¹ (C_q M⁻¹ b_top − b_bottom),   q̈ = M⁻¹ (b_top − C_qᵀ λ)
//! ```
//!
//! `M` is block diagonal (one block per body), so `M⁻¹` is formed block by block, and `S` is assembled
//! from the body blocks of `C_q`: `S_ij = Σ_b C_i,b M_b⁻¹ C_j,bᵀ` over the bodies `b` that rows `i`
//! and `j` share. `S` is factored by a dense Cholesky in storage allocated once; singular `S`
//! (rank-deficient `C_q`) is detected from the Cholesky pivots.
//!
//! Coordinates without inertia (a point mass's angle, a massless body whose reference point is its
//! centre of mass) are kept as unknowns `q̈_z` of a reduced saddle-point system over the rest:
//!
//! ```text
//! [ 0    C_zᵀ ] [ q̈_z ]   [ b_z                      ]
//! [ C_z  −S   ] [ λ   ] = [ b_bottom − C_a M_a⁻¹ b_a  ]
//! ```
//!
//! (size `z + m`, factored by LU with partial pivoting), then `q̈_a = M_a⁻¹ (b_a − C_aᵀ λ)`.

use super::SingularKkt;
use crate::blocks::MAX_BLOCK;
use crate::linalg::SmallLu;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintValues};

pub(crate) struct SchurKkt {
    n: usize,
    m: usize,
    /// For each body: `(row, index of the row's first Jacobian entry on that body)`.
    rows_of_body: Vec<Vec<(usize, usize)>>,
    minv: InverseMass,
    /// `S`, then its Cholesky factor (lower triangle), row-major `m × m`.
    s: Vec<f64>,
    pivot_tolerance: f64,
    tmp_m: Vec<f64>,
    tmp_n: Vec<f64>,
    jacobian: Vec<f64>,
    /// Coordinates without inertia.
    massless: Vec<usize>,
    /// Jacobian entries on massless coordinates: `(entry, row, index in massless)`.
    massless_entries: Vec<(usize, usize, usize)>,
    /// LU of the reduced system when there are massless coordinates.
    reduced: Option<SmallLu>,
    /// When every massless coordinate appears in exactly one equation, and that equation involves
    /// no coordinate with inertia (a point mass's angle held by a prismatic joint), the reduced
    /// system decouples: `(coordinate, row, coefficient)` per massless coordinate, solved directly,
    /// and the rest by the Cholesky of `S` (identity on those rows). Empty when it does not apply.
    decoupled: Vec<(usize, usize, f64)>,
    /// Scratch: number of non-zero entries per massless coordinate (decoupling check).
    counts: Vec<usize>,
    tmp_r: Vec<f64>,
    /// Condition estimate of the last factorization (squared Cholesky pivot ratio, or the reduced
    /// LU's pivot ratio).
    pub condition: f64,
}

/// True when the Schur back end can run: every body's mass block is positive definite, or is
/// diagonal with zero entries (no mass, or no inertia, at the reference point), and the reduced
/// system over the coordinates without inertia stays small.
pub(crate) fn applicable(mass: &BlockDiagonal, m: usize) -> bool {
    let mut inv = [0.0; MAX_BLOCK * MAX_BLOCK];
    let ok = (0..mass.num_blocks()).all(|b| {
        let s = mass.size(b);
        s <= MAX_BLOCK && (mass.invert_block(b, &mut inv[..s * s]) || mass.block_is_diagonal(b))
    });
    let z = mass.zero_diagonal().len();
    ok && (z == 0 || z + m <= 64)
}

impl SchurKkt {
    pub fn new(
        mass: &BlockDiagonal,
        mass_is_constant: bool,
        pattern: &ConstraintPattern,
        pivot_tolerance: f64,
    ) -> Self {
        let n = pattern.cols();
        let m = pattern.rows();
        let massless = mass.zero_diagonal();
        let massless_entries: Vec<(usize, usize, usize)> = pattern
            .entries()
            .iter()
            .enumerate()
            .filter_map(|(e, &(r, c))| massless.iter().position(|&z| z == c).map(|k| (e, r, k)))
            .collect();
        // At most one entry per massless Jacobian entry: sized here, so that the number of entries
        // a state makes non-zero (round-off included) never grows it while stepping.
        let decoupled = Vec::with_capacity(massless_entries.len());
        let p = massless.len() + m;
        let reduced = (!massless.is_empty()).then(|| SmallLu::new(p));
        let mut rows_of_body = vec![Vec::new(); mass.num_blocks()];
        for s in pattern.segments() {
            rows_of_body[s.body].push((s.row, s.first));
        }
        SchurKkt {
            n,
            m,
            rows_of_body,
            minv: InverseMass::new(mass, mass_is_constant),
            s: vec![0.0; m * m],
            pivot_tolerance,
            tmp_m: vec![0.0; m],
            tmp_n: vec![0.0; n],
            jacobian: vec![0.0; pattern.entries().len()],
            massless,
            massless_entries,
            reduced,
            tmp_r: vec![0.0; p],
            decoupled,
            counts: vec![0; p - m],
            condition: 1.0,
        }
    }

    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        _pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        self.minv.update(mass, true)?;
        let m = self.m;
        self.s.iter_mut().for_each(|v| *v = 0.0);
        let jac = &vals.jacobian;
        for (b, rows) in self.rows_of_body.iter().enumerate() {
            let len = self.minv.blocks.size(b);
            let w = self.minv.blocks.block(b);
            for &(i, ei) in rows {
                // S_ij += C_i,b M_b⁻¹ C_j,bᵀ: for planar bodies with w_i = M_b⁻¹ C_i,bᵀ in registers.
                if len == 3 {
                    let (c0, c1, c2) = (jac[ei], jac[ei + 1], jac[ei + 2]);
                    let w0 = w[0] * c0 + w[1] * c1 + w[2] * c2;
                    let w1 = w[3] * c0 + w[4] * c1 + w[5] * c2;
                    let w2 = w[6] * c0 + w[7] * c1 + w[8] * c2;
                    for &(j, ej) in rows {
                        if j <= i {
                            self.s[i * m + j] += w0 * jac[ej] + w1 * jac[ej + 1] + w2 * jac[ej + 2];
                        }
                    }
                } else {
                    let mut wi = [0.0; MAX_BLOCK];
                    self.minv.blocks.block_mul(b, &jac[ei..ei + len], &mut wi[..len]);
                    for &(j, ej) in rows {
                        if j <= i {
                            self.s[i * m + j] += (0..len).map(|r| wi[r] * jac[ej + r]).sum::<f64>();
                        }
                    }
                }
            }
        }
        self.decoupled.clear();
        if self.reduced.is_some() && self.try_decouple(jac) {
            for &(_, r, _) in &self.decoupled {
                self.s[r * m + r] = 1.0;
            }
        } else if let Some(lu) = &mut self.reduced {
            self.decoupled.clear();
            // [0 C_zᵀ; C_z −S]
            let z = self.massless.len();
            let p = z + m;
            lu.a.iter_mut().for_each(|v| *v = 0.0);
            for i in 0..m {
                for j in 0..=i {
                    let v = -self.s[i * m + j];
                    lu.a[(z + i) * p + z + j] = v;
                    lu.a[(z + j) * p + z + i] = v;
                }
            }
            for &(e, r, k) in &self.massless_entries {
                lu.a[k * p + z + r] += jac[e];
                lu.a[(z + r) * p + k] += jac[e];
            }
            let (smallest, largest) = lu.factor();
            let regular = smallest > self.pivot_tolerance * largest;
            if !regular {
                return Err(SingularKkt(format!(
                    "reduced system pivot ratio {:.3e}",
                    smallest / largest
                )));
            }
            self.jacobian.copy_from_slice(jac);
            return Ok(());
        }
        // Cholesky, lower triangle in place.
        let mut largest = 0.0f64;
        for i in 0..m {
            largest = largest.max(self.s[i * m + i]);
        }
        let (mut lmin, mut lmax) = (f64::INFINITY, 0.0f64);
        for j in 0..m {
            let mut d = self.s[j * m + j];
            for k in 0..j {
                d -= self.s[j * m + k] * self.s[j * m + k];
            }
            let regular = d > self.pivot_tolerance * largest;
            if !regular {
                return Err(SingularKkt(format!(
                    "Schur complement pivot {d:.3e} (largest diagonal {largest:.3e})"
                )));
            }
            let d = d.sqrt();
            lmin = lmin.min(d);
            lmax = lmax.max(d);
            self.s[j * m + j] = d;
            for i in j + 1..m {
                let mut v = self.s[i * m + j];
                for k in 0..j {
                    v -= self.s[i * m + k] * self.s[j * m + k];
                }
                self.s[i * m + j] = v / d;
            }
        }
        self.jacobian.copy_from_slice(jac);
        self.condition = if lmin > 0.0 {
            (lmax / lmin).powi(2)
        } else {
            f64::INFINITY
        };
        Ok(())
    }

    /// Fills `decoupled` when each massless coordinate has exactly one non-zero Jacobian entry, in
    /// a row no other massless coordinate uses and whose `S` diagonal is zero (no inertia in it).
    fn try_decouple(&mut self, jac: &[f64]) -> bool {
        let m = self.m;
        self.counts.iter_mut().for_each(|c| *c = 0);
        for &(e, r, k) in &self.massless_entries {
            if jac[e] != 0.0 {
                self.counts[k] += 1;
                self.decoupled.push((self.massless[k], r, jac[e]));
            }
        }
        let ok = self.counts.iter().all(|&c| c == 1)
            && self.decoupled.iter().all(|&(_, r, _)| self.s[r * m + r] == 0.0)
            && self
                .decoupled
                .iter()
                .enumerate()
                .all(|(i, a)| self.decoupled[..i].iter().all(|b| b.1 != a.1));
        if !ok {
            self.decoupled.clear();
        }
        ok
    }

    pub fn solve(&mut self, pattern: &ConstraintPattern, x: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        let (top, bottom) = x.split_at_mut(n);
        // tmp_m = C M⁻¹ b_top − b_bottom
        self.minv.apply(top, &mut self.tmp_n);
        self.tmp_m.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in pattern.entries().iter().zip(&self.jacobian) {
            self.tmp_m[r] += v * self.tmp_n[c];
        }
        for (t, b) in self.tmp_m.iter_mut().zip(bottom.iter()) {
            *t -= b;
        }
        // Decoupled massless coordinates: λ_r = b_z / c and q̈_z = b_r / c for each (z, r, c).
        let mut qz = [0.0f64; 8];
        let decoupled = !self.decoupled.is_empty() && self.decoupled.len() <= qz.len();
        if decoupled {
            for (k, &(c, r, v)) in self.decoupled.iter().enumerate() {
                self.tmp_m[r] = top[c] / v;
                qz[k] = bottom[r] / v;
            }
        }
        if let (Some(lu), false) = (&self.reduced, decoupled) {
            let z = self.massless.len();
            for (k, &c) in self.massless.iter().enumerate() {
                self.tmp_r[k] = top[c];
            }
            for i in 0..m {
                self.tmp_r[z + i] = -self.tmp_m[i];
            }
            lu.solve(&mut self.tmp_r);
            self.tmp_m.copy_from_slice(&self.tmp_r[z..]);
            bottom.copy_from_slice(&self.tmp_m);
            for (&(r, c), &v) in pattern.entries().iter().zip(&self.jacobian) {
                top[c] -= v * self.tmp_m[r];
            }
            self.minv.apply(top, &mut self.tmp_n);
            top.copy_from_slice(&self.tmp_n);
            for (k, &c) in self.massless.iter().enumerate() {
                top[c] = self.tmp_r[k];
            }
            return;
        }
        // λ = S⁻¹ tmp_m (forward and back substitution with the Cholesky factor).
        for i in 0..m {
            let mut v = self.tmp_m[i];
            for k in 0..i {
                v -= self.s[i * m + k] * self.tmp_m[k];
            }
            self.tmp_m[i] = v / self.s[i * m + i];
        }
        for i in (0..m).rev() {
            let mut v = self.tmp_m[i];
            for k in i + 1..m {
                v -= self.s[k * m + i] * self.tmp_m[k];
            }
            self.tmp_m[i] = v / self.s[i * m + i];
        }
        bottom.copy_from_slice(&self.tmp_m);
        // q̈ = M⁻¹ (b_top − C_qᵀ λ)
        for (&(r, c), &v) in pattern.entries().iter().zip(&self.jacobian) {
            top[c] -= v * self.tmp_m[r];
        }
        self.minv.apply(top, &mut self.tmp_n);
        top.copy_from_slice(&self.tmp_n);
        if decoupled {
            for (k, &(c, _, _)) in self.decoupled.iter().enumerate() {
                top[c] = qz[k];
            }
        }
    }
}

/// `M⁻¹` block by block, recomputed only when the mass matrix depends on the configuration.
pub(crate) struct InverseMass {
    /// The inverse blocks.
    pub blocks: BlockDiagonal,
    valid: bool,
    constant: bool,
}

impl InverseMass {
    pub fn new(mass: &BlockDiagonal, constant: bool) -> Self {
        InverseMass {
            blocks: mass.clone(),
            valid: false,
            constant,
        }
    }

    /// Refreshes the inverse when needed. With `allow_diagonal`, a diagonal block with zero entries
    /// (no mass or no inertia) is inverted on its non-zero part only; otherwise every block must be
    /// positive definite.
    pub fn update(&mut self, mass: &BlockDiagonal, allow_diagonal: bool) -> Result<(), SingularKkt> {
        if self.valid && self.constant {
            return Ok(());
        }
        for b in 0..mass.num_blocks() {
            if mass.invert_block(b, self.blocks.block_mut(b)) {
                continue;
            }
            if !(allow_diagonal && mass.block_is_diagonal(b)) {
                return Err(SingularKkt(
                    "mass block not positive definite (nor diagonal where allowed)".into(),
                ));
            }
            let s = mass.size(b);
            let inv = self.blocks.block_mut(b);
            for (k, v) in inv.iter_mut().enumerate() {
                let d = mass.get(b, k / s, k % s);
                *v = if k / s == k % s && d > 0.0 { 1.0 / d } else { 0.0 };
            }
        }
        self.valid = self.constant;
        Ok(())
    }

    /// `y ← M⁻¹ x` block by block.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        self.blocks.mul_add(1.0, x, y);
    }
}
