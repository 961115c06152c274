//! Range-space (Schur complement) back end for a positive definite mass matrix:
//!
//! ```text
//! S = C_q M⁻¹ C_qᵀ,   λ = S⁻¹ (C_q M⁻¹ b_top − b_bottom),   q̈ = M⁻¹ (b_top − C_qᵀ λ)
//! ```
//!
//! `M` is block diagonal (3×3 per body), so `M⁻¹` is formed block by block, and `S` is assembled
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

use super::small_lu::SmallLu;
use super::SingularKkt;
use dalembert_constraints::{ConstraintSystem, ConstraintValues};
use dalembert_kinematics::{Body, MassMatrix, Vec2};
use nalgebra::{Matrix3, Vector3};

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
/// diagonal (centre of mass at the reference point) with zero entries, and the reduced system over
/// the massless coordinates stays small.
pub(crate) fn applicable(bodies: &[Body], m: usize) -> bool {
    let ok = bodies
        .iter()
        .all(|b| (b.mass > 0.0 && b.inertia > 0.0) || b.center_of_mass == Vec2::zeros());
    let z = massless_coordinates(bodies).len();
    ok && (z == 0 || z + m <= 64)
}

fn massless_coordinates(bodies: &[Body]) -> Vec<usize> {
    let mut z = Vec::new();
    for (i, b) in bodies.iter().enumerate() {
        if b.mass > 0.0 && b.inertia_about_reference() > 0.0 && (b.inertia > 0.0 || b.center_of_mass == Vec2::zeros()) {
            continue;
        }
        if b.mass == 0.0 {
            z.extend([3 * i, 3 * i + 1]);
        }
        if b.inertia_about_reference() == 0.0 {
            z.push(3 * i + 2);
        }
    }
    z
}

impl SchurKkt {
    pub fn new(sys: &ConstraintSystem, bodies: &[Body], pivot_tolerance: f64) -> Self {
        let n = sys.num_coordinates();
        let m = sys.num_equations();
        let massless = massless_coordinates(bodies);
        let massless_entries = sys
            .pattern()
            .iter()
            .enumerate()
            .filter_map(|(e, &(r, c))| massless.iter().position(|&z| z == c).map(|k| (e, r, k)))
            .collect();
        let p = massless.len() + m;
        let reduced = (!massless.is_empty()).then(|| SmallLu::new(p));
        let mut rows_of_body = vec![Vec::new(); n / 3];
        for (e, &(r, c)) in sys.pattern().iter().enumerate() {
            if c % 3 == 0 {
                rows_of_body[c / 3].push((r, e));
            }
        }
        SchurKkt {
            n,
            m,
            rows_of_body,
            minv: InverseMass::new(n / 3),
            s: vec![0.0; m * m],
            pivot_tolerance,
            tmp_m: vec![0.0; m],
            tmp_n: vec![0.0; n],
            jacobian: vec![0.0; sys.pattern().len()],
            massless,
            massless_entries,
            reduced,
            tmp_r: vec![0.0; p],
            decoupled: Vec::new(),
            counts: vec![0; p - m],
            condition: 1.0,
        }
    }

    pub fn factor(
        &mut self,
        mass: &MassMatrix,
        _sys: &ConstraintSystem,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        self.minv.update(mass, true)?;
        let m = self.m;
        self.s.iter_mut().for_each(|v| *v = 0.0);
        let jac = &vals.jacobian;
        for (b, rows) in self.rows_of_body.iter().enumerate() {
            let minv = &self.minv.blocks[b];
            for &(i, ei) in rows {
                let ci = Vector3::new(jac[ei], jac[ei + 1], jac[ei + 2]);
                let wi = minv * ci;
                for &(j, ej) in rows {
                    if j <= i {
                        self.s[i * m + j] += wi.x * jac[ej] + wi.y * jac[ej + 1] + wi.z * jac[ej + 2];
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

    pub fn solve(&mut self, sys: &ConstraintSystem, x: &mut [f64]) {
        let (n, m) = (self.n, self.m);
        let (top, bottom) = x.split_at_mut(n);
        // tmp_m = C M⁻¹ b_top − b_bottom
        self.minv.apply(top, &mut self.tmp_n);
        self.tmp_m.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in sys.pattern().iter().zip(&self.jacobian) {
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
            for (&(r, c), &v) in sys.pattern().iter().zip(&self.jacobian) {
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
        for (&(r, c), &v) in sys.pattern().iter().zip(&self.jacobian) {
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
    /// One inverse 3×3 block per body.
    pub blocks: Vec<Matrix3<f64>>,
    valid: bool,
}

impl InverseMass {
    pub fn new(bodies: usize) -> Self {
        InverseMass {
            blocks: vec![Matrix3::zeros(); bodies],
            valid: false,
        }
    }

    /// Refreshes the inverse when needed. With `allow_diagonal`, a diagonal block with zero entries
    /// (no mass or no inertia) is inverted on its non-zero part only; otherwise every block must be
    /// positive definite.
    pub fn update(&mut self, mass: &MassMatrix, allow_diagonal: bool) -> Result<(), SingularKkt> {
        if self.valid && !mass.is_configuration_dependent() {
            return Ok(());
        }
        for (mi, blk) in self.blocks.iter_mut().zip(mass.blocks()) {
            *mi = match blk.cholesky() {
                Some(c) => c.inverse(),
                None if allow_diagonal
                    && (blk - Matrix3::from_diagonal(&blk.diagonal()))
                        .iter()
                        .all(|v| *v == 0.0) =>
                {
                    Matrix3::from_diagonal(&blk.diagonal().map(|d| if d > 0.0 { 1.0 / d } else { 0.0 }))
                }
                None => {
                    return Err(SingularKkt(
                        "mass block not positive definite (nor diagonal where allowed)".into(),
                    ))
                }
            };
        }
        self.valid = !mass.is_configuration_dependent();
        Ok(())
    }

    /// `y ← M⁻¹ x` block by block.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        for (b, mi) in self.blocks.iter().enumerate() {
            let v = mi * Vector3::new(x[3 * b], x[3 * b + 1], x[3 * b + 2]);
            y[3 * b..3 * b + 3].copy_from_slice(v.as_slice());
        }
    }
}
