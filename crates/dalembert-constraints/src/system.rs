//! Assembly of all planar constraints into `C`, `C_q` (sparse, fixed pattern), `C_t` and `Q_d`: the
//! planar implementation of the seam's [`ConstraintSet`].

use crate::{Constraint, ConstraintEval};
use dalembert_kinematics::{BodyRef, BodyState, Coordinates};
use dalembert_system::{ConstraintError, EquationRef};
use dalembert_system::{ConstraintPattern, ConstraintSet, ConstraintValues, Layout};

/// The planar coordinate labels of one body (positions and velocities alike: `v = q̇`).
pub const PLANAR_LABELS: &[&str] = &["x", "y", "angle"];

/// Every constraint of a planar model, with the row layout and the sparsity pattern of `C_q`.
///
/// Rows follow the constraints in order. The pattern lists, per constraint, the entries of each
/// moving body's 3-column block, row by row; it is computed once and never changes, so consumers
/// can map entries into their own sparse matrices once at setup.
#[derive(Debug)]
pub struct ConstraintSystem {
    constraints: Vec<Box<dyn Constraint>>,
    coordinates: Coordinates,
    row_offsets: Vec<usize>,
    entry_offsets: Vec<usize>,
    pattern: ConstraintPattern,
}

impl ConstraintSystem {
    /// Builds the system for `bodies` moving bodies; validates every constraint.
    pub fn new(bodies: usize, constraints: Vec<Box<dyn Constraint>>) -> Result<Self, ConstraintError> {
        let mut row_offsets = vec![0];
        let mut entry_offsets = vec![0];
        let mut segments = Vec::new();
        for c in &constraints {
            let name = c.name().to_string();
            // Bodies first: a joint built against a body the model lacks is named as such.
            for body in c.bodies() {
                dalembert_kinematics::forces::check_body(&format!("constraint '{name}'"), body, bodies)?;
            }
            c.validate()?;
            let ne = c.num_equations();
            if !(1..=crate::MAX_EQUATIONS).contains(&ne) {
                return Err(ConstraintError::EquationCount { name, count: ne });
            }
            let [a, b] = c.bodies();
            if a == b {
                return Err(ConstraintError::SameBody { name });
            }
            let r0 = *row_offsets.last().unwrap_or(&0);
            for body in [a, b] {
                if let BodyRef::Body(id) = body {
                    segments.extend((0..ne).map(|k| (r0 + k, id.0)));
                }
            }
            row_offsets.push(r0 + ne);
            entry_offsets.push(3 * segments.len());
        }
        let layout = Layout::new((0..bodies).map(|_| ("", PLANAR_LABELS, PLANAR_LABELS)));
        let pattern = ConstraintPattern::from_segments(*row_offsets.last().unwrap_or(&0), &layout, segments);
        Ok(ConstraintSystem {
            constraints,
            coordinates: Coordinates::new(bodies),
            row_offsets,
            entry_offsets,
            pattern,
        })
    }

    /// The coordinate layout.
    pub fn coordinates(&self) -> Coordinates {
        self.coordinates
    }

    /// The constraints, in row order.
    pub fn constraints(&self) -> &[Box<dyn Constraint>] {
        &self.constraints
    }

    /// First row of constraint `k`.
    #[inline]
    pub fn row_offset(&self, k: usize) -> usize {
        self.row_offsets[k]
    }

    /// The state of `body` from the positions, the velocities (empty: at rest) and the sines and
    /// cosines cached in `values.scratch` by the last [`ConstraintSet::evaluate`].
    fn state(body: BodyRef, q: &[f64], qd: &[f64], scratch: &[f64]) -> BodyState {
        match body {
            BodyRef::Ground => BodyState::GROUND,
            BodyRef::Body(id) => BodyState::of_with_rotation(body, q, qd, scratch[2 * id.0], scratch[2 * id.0 + 1]),
        }
    }

    /// The Jacobian blocks of constraint `k` from assembled values: `(first, second)`, each a slice
    /// of `3 × equations` entries row by row, or `None` for the ground.
    pub fn blocks<'a>(&self, k: usize, values: &'a ConstraintValues) -> [Option<&'a [f64]>; 2] {
        let [a, b] = self.constraints[k].bodies();
        let ne = self.row_offsets[k + 1] - self.row_offsets[k];
        let mut e = self.entry_offsets[k];
        let mut out = [None, None];
        for (side, body) in [a, b].into_iter().enumerate() {
            if body != BodyRef::Ground {
                out[side] = Some(&values.jacobian[e..e + 3 * ne]);
                e += 3 * ne;
            }
        }
        out
    }
}

impl ConstraintSet for ConstraintSystem {
    fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }

    fn equation(&self, row: usize) -> EquationRef {
        let k = self.row_offsets.partition_point(|&r| r <= row) - 1;
        let c = &self.constraints[k];
        let e = row - self.row_offsets[k];
        EquationRef {
            constraint: k,
            name: c.name().to_string(),
            equation: e,
            label: c.equation_label(e),
        }
    }

    /// Storage sized for this system; the scratch holds one sine and cosine per body.
    fn values(&self) -> ConstraintValues {
        ConstraintValues::new(&self.pattern, 2 * self.coordinates.bodies())
    }

    /// Evaluates every constraint (one `sin_cos` per body, cached in `out.scratch`). Allocates nothing.
    fn evaluate(&self, t: f64, q: &[f64], qd: &[f64], out: &mut ConstraintValues) {
        let mut eval = ConstraintEval::default();
        for (i, sc) in out.scratch.chunks_exact_mut(2).enumerate() {
            let (s, c) = q[3 * i + 2].sin_cos();
            sc[0] = s;
            sc[1] = c;
        }
        for (k, c) in self.constraints.iter().enumerate() {
            let [a, b] = c.bodies();
            let (sa, sb) = (Self::state(a, q, qd, &out.scratch), Self::state(b, q, qd, &out.scratch));
            c.evaluate(t, &sa, &sb, &mut eval);
            let r0 = self.row_offsets[k];
            let ne = self.row_offsets[k + 1] - r0;
            out.c[r0..r0 + ne].copy_from_slice(&eval.c[..ne]);
            out.c_t[r0..r0 + ne].copy_from_slice(&eval.c_t[..ne]);
            out.gamma[r0..r0 + ne].copy_from_slice(&eval.gamma[..ne]);
            let mut e = self.entry_offsets[k];
            for (side, body) in [a, b].into_iter().enumerate() {
                if body != BodyRef::Ground {
                    for row in eval.jac.iter().take(ne) {
                        out.jacobian[e..e + 3].copy_from_slice(&row[side]);
                        e += 3;
                    }
                }
            }
        }
    }

    fn describe_position(&self, i: usize) -> String {
        let (b, c) = self.coordinates.owner(i);
        format!("coordinate {c} of body #{}", b.0)
    }
}
