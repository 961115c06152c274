//! Errors of constraint assembly and kinematic analysis. Each names the constraints at fault.

use crate::ModelError;
use std::fmt;
use thiserror::Error;

/// One scalar equation of a named constraint.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EquationRef {
    /// Index of the constraint in the system.
    pub constraint: usize,
    /// Its name.
    pub name: String,
    /// Equation index within the constraint.
    pub equation: usize,
    /// Label of the equation (`x`, `y`, `angle`, …).
    pub label: &'static str,
}

impl fmt::Display for EquationRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "'{}' ({})", self.name, self.label)
    }
}

/// At most this many equations are listed in a message; the rest are counted.
const LISTED: usize = 12;

fn truncated(mut items: Vec<String>) -> String {
    let more = items.len().saturating_sub(LISTED);
    items.truncate(LISTED);
    let mut s = items.join(", ");
    if more > 0 {
        s.push_str(&format!(" and {more} more"));
    }
    s
}

/// The equations for a one-line message: the first twelve by name, the rest counted
/// (`'J1' (x), 'J1' (y), … and 109 more`).
pub fn list(eqs: &[EquationRef]) -> String {
    truncated(eqs.iter().map(|e| e.to_string()).collect())
}

fn list_violated(v: &[(EquationRef, f64)]) -> String {
    // Largest violations first.
    let mut v: Vec<&(EquationRef, f64)> = v.iter().collect();
    v.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    truncated(v.iter().map(|(e, r)| format!("{e} by {r:.3e}")).collect())
}

/// What can go wrong building a constraint system or analysing its kinematics.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ConstraintError {
    /// A constraint's own data is invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A constraint connects a body to itself.
    #[error("constraint '{name}': both ends are the same body")]
    SameBody {
        /// Constraint name.
        name: String,
    },
    /// A constraint has an unsupported number of equations.
    #[error("constraint '{name}': {count} equations (1 to 3 supported)")]
    EquationCount {
        /// Constraint name.
        name: String,
        /// Its count.
        count: usize,
    },
    /// Newton–Raphson on `C(q, t) = 0` did not converge.
    #[error("position analysis at t = {t}: not converged after {iterations} iterations; still violated: {}", list_violated(.violated), t = crate::Shortest(*.time))]
    NotConverged {
        /// Time of the analysis.
        time: f64,
        /// Iterations spent.
        iterations: usize,
        /// Equations still violated, with their residuals.
        violated: Vec<(EquationRef, f64)>,
    },
    /// The constraint Jacobian lost rank where a unique solution is required, and the equations are
    /// inconsistent there (a toggle or dead-centre position, or a locked mechanism).
    #[error("singular constraint Jacobian at t = {t} (rank {rank} of {equations_count}); equations involved: {}", list(.involved), t = crate::Shortest(*.time))]
    Singular {
        /// Time of the analysis.
        time: f64,
        /// Numerical rank of `C_q`.
        rank: usize,
        /// Number of equations.
        equations_count: usize,
        /// Equations in the dependent set (left null space of `C_q`).
        involved: Vec<EquationRef>,
    },
    /// A dense matrix would need more memory than is reasonable (more than
    /// [`crate::structure::DENSE_LIMIT_BYTES`]): the analysis or formulation refuses the model.
    #[error("{what}: a dense {rows} × {cols} matrix ({:.1} GiB) would be needed; {hint}", (*.rows as f64) * (*.cols as f64) * 8.0 / 1073741824.0)]
    TooLarge {
        /// The analysis.
        what: String,
        /// What to do instead.
        hint: &'static str,
        /// Rows of the dense matrix.
        rows: usize,
        /// Columns of the dense matrix.
        cols: usize,
    },
    /// The state or a constraint value is not finite.
    #[error("non-finite value at t = {t}: {what}", t = crate::Shortest(*.time))]
    NonFinite {
        /// Time.
        time: f64,
        /// What was not finite.
        what: String,
    },
}

impl ConstraintError {
    /// [`ConstraintError::NotConverged`] at `t` after `iterations`, listing the equations of `sys`
    /// whose residual in `c` is above `tolerance` or not a number.
    pub fn not_converged<S: crate::ConstraintSet + ?Sized>(
        sys: &S,
        c: &[f64],
        t: f64,
        iterations: usize,
        tolerance: f64,
    ) -> Self {
        let violated = c
            .iter()
            .enumerate()
            .filter(|(_, c)| c.abs() > tolerance || c.is_nan())
            .map(|(r, c)| (sys.equation(r), *c))
            .collect();
        ConstraintError::NotConverged {
            time: t,
            iterations,
            violated,
        }
    }
}
