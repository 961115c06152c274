//! Storage and factorization of the saddle-point ("KKT") matrix `[M C_qᵀ; C_q 0]` (`docs/equations.md`
//! §3), chosen once per system by [`Backend`] and refactored in place each evaluation.

mod dense;
mod schur;
mod sparse;
mod sparse_schur;
mod tree;

use dense::DenseKkt;
use schur::SchurKkt;
use sparse::SparseKkt;
use sparse_schur::SparseSchurKkt;
use tree::TreeKkt;

use super::LinalgError;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintSet, ConstraintValues};

/// The back ends' failure: a message (turned into [`LinalgError::Singular`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SingularKkt(pub String);

impl From<SingularKkt> for LinalgError {
    fn from(e: SingularKkt) -> Self {
        LinalgError::Singular(e.0)
    }
}

/// Which linear-algebra back end solves the saddle-point system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Backend {
    /// The tree factorization for systems without loops whose mass blocks are all positive definite,
    /// at any size, and above the dense limit also with up to [`TREE_CUTS_UP_TO`] loop-closing
    /// equations (a coupling between joint values, one spatial loop). Otherwise, up to the dense limit (`n + m` unknowns): the Schur complement when
    /// the mass blocks allow it (positive definite or diagonal), dense LU otherwise; above it the
    /// sparse Schur complement when every mass block is positive definite; with singular mass
    /// blocks the dense back ends up to twice the limit and the sparse LU above.
    ///
    /// One evaluation, tree / dense Schur complement (a loop of `Augmented::accelerations`,
    /// 2026-11-25): planar chains of 1, 3 and 8 links 0.156 / 0.178, 0.385 / 0.432 and 0.948 / 1.263
    /// µs; spatial `chain3d` of 1, 2 and 8 links 0.387 / 0.390, 0.885 / 0.975 and 3.47 / 8.65 µs. With
    /// loops the tree is not chosen: on the four-bar it is slower (0.595 / 0.525 µs), and near the
    /// singular positions of the IFToMM A02 N-four-bar its different rounding moved which step sizes
    /// lose the branch without a stop (N = 4, RK4 + projection at 0.5 ms: 2.6e-3 with the tree, 1.4e-4
    /// with the Schur complement), so closed chains keep the back ends their robustness figures
    /// (`docs/stability.md`) were measured with. A tree in joint coordinates without constraint
    /// equations ([`crate::MultibodySystem::kinematic_tree`]) is solved by the articulated-body
    /// algorithm ([`crate::tree::Articulated`]), the O(n) factorization of its `M`.
    #[default]
    Auto,
    /// Dense LU with partial pivoting of the whole saddle-point matrix.
    Dense,
    /// Range space: Cholesky of `S = C_q M⁻¹ C_qᵀ`, with a small reduced system for coordinates
    /// without inertia (needs mass blocks that are positive definite, or diagonal).
    Schur,
    /// Sparse LU of the saddle-point matrix with a symbolic analysis reused across evaluations.
    Sparse,
    /// Sparse Cholesky of `S = C_q M⁻¹ C_qᵀ` (positive definite mass blocks), symbolic analysis
    /// reused: linear cost for chains.
    SparseSchur,
    /// Block `L D Lᵀ` of the whole matrix along the body–joint tree (no fill-in: linear cost with
    /// small dense blocks), loops closed by the Schur complement of the cut equations (needs
    /// positive definite mass blocks of 3 or 6 velocities, the planar and spatial bodies, and at
    /// most as many equations between two bodies as a body has velocities).
    Tree,
}

/// Condition estimate of the Schur complement `C_q M⁻¹ C_qᵀ` above which [`Backend::Auto`] factors
/// the whole saddle-point matrix by LU instead (from the same values, set up at construction).
///
/// The Schur complement squares the conditioning of `C_q M^-1/2`, so near a singular position of a
/// closed chain it loses twice the digits the LU of the whole matrix loses. 1e8 ≈ 1/√ε is where it
/// has lost half of them. Measured on the IFToMM A02 N-four-bar (N = 40, augmented, RK4 +
/// projection, 20 s, B₀ error, h = 2, 1, 0.5, 0.25, 0.1 ms; `cargo run --release --example
/// n_four_bar`): with the Schur complement alone 0.42 (on another branch, silently), 2.9e-5, 9.3e-6,
/// 2.6e-4, stopped at 8.58 s ("singular"); with this fallback 1.6e-5, 4.7e-6, a branch switch
/// (stopped by `dalembert_integrators::IntegrationError::BranchSwitch`), 5.5e-6, 1.4e-3. A lower threshold helps
/// that benchmark no more reliably (1e4: 1.0e-4 … 2.0e-3, no switch) and falls back on every step
/// of well-posed spatial scenes whose Schur complement is merely badly scaled (`scenes/arm-6.toml`,
/// `scenes/slider-crank-3d.toml`); at 1e8 no shipped scene and no chain of 64 or 256 falls back
/// (`dalembert simulate`, RK4 at 1 ms, 5 s).
pub const SCHUR_FALLBACK_CONDITION: f64 = 1e8;

/// Most loop-closing (cut) equations with which [`Backend::Auto`] still takes the tree back end for
/// a system above the dense limit: one spatial loop (6 equations), or a few couplings between joint
/// values. The cut equations' dense Schur complement costs one tree solve each, so a handful keeps
/// the tree's linear cost; the Panda, whose second finger is coupled to the first (one cut
/// equation), steps in 78–108 µs (RK4, 1 ms) where the sparse Schur complement took 142–171 µs
/// (three runs of `cargo run --release --example backends -- scenes/robots/panda.urdf`,
/// 2026-11-27). Closed chains with more loops (IFToMM A02's N-four-bar: 2 per loop) keep the
/// sparse Schur complement their robustness figures were measured with.
pub const TREE_CUTS_UP_TO: usize = 6;

/// The saddle-point matrix of one system, factored by the back end chosen at construction.
pub struct SaddlePoint {
    kind: Kind,
    /// For a Schur or tree back end chosen by [`Backend::Auto`]: the LU of the whole matrix (dense below
    /// the dense limit, sparse above), set up at construction and factored instead when the Schur
    /// complement is singular or its condition estimate exceeds [`SCHUR_FALLBACK_CONDITION`].
    fallback: Option<Kind>,
    /// Whether the last factorization is the fallback's.
    on_fallback: bool,
}

impl std::fmt::Debug for SaddlePoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SaddlePoint").field("backend", &self.name()).finish()
    }
}

enum Kind {
    Dense(Box<DenseKkt>),
    Schur(Box<SchurKkt>),
    Sparse(Box<SparseKkt>),
    SparseSchur(Box<SparseSchurKkt>),
    Tree(Box<TreeKkt>),
}

impl Kind {
    fn factor(
        &mut self,
        mass: &BlockDiagonal,
        pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), LinalgError> {
        Ok(match self {
            Kind::Dense(d) => d.factor(mass, pattern, vals),
            Kind::Schur(s) => s.factor(mass, pattern, vals),
            Kind::Sparse(s) => s.factor(mass, pattern, vals),
            Kind::SparseSchur(s) => s.factor(mass, pattern, vals),
            Kind::Tree(t) => t.factor(mass, pattern, vals),
        }?)
    }

    fn solve(&mut self, pattern: &ConstraintPattern, x: &mut [f64]) {
        match self {
            Kind::Dense(d) => d.solve(x),
            Kind::Schur(s) => s.solve(pattern, x),
            Kind::Sparse(s) => s.solve(x),
            Kind::SparseSchur(s) => s.solve(pattern, x),
            Kind::Tree(t) => t.solve(x),
        }
    }
}

/// True when every mass block is positive definite (the Schur complements and the tree need it).
fn positive_definite(mass: &BlockDiagonal) -> bool {
    mass.clone().invert_blocks(&mut mass.clone()).is_ok()
}

/// `Auto` resolved for a system with mass matrix `mass` and constraint pattern `pattern`: the back
/// end [`SaddlePoint::new`] would build.
pub fn resolve(backend: Backend, mass: &BlockDiagonal, pattern: &ConstraintPattern, dense_limit: usize) -> Backend {
    let (n, m) = (mass.dim(), pattern.rows());
    let spd = positive_definite(mass);
    let cuts = tree::cut_rows(pattern, mass);
    let loop_free = cuts == Some(0);
    let few_cuts = cuts.is_some_and(|k| k <= TREE_CUTS_UP_TO);
    match backend {
        Backend::Auto if spd && loop_free => Backend::Tree,
        Backend::Auto if spd && few_cuts && n + m > dense_limit => Backend::Tree,
        Backend::Auto if n + m > dense_limit && spd => Backend::SparseSchur,
        Backend::Auto if n + m > 2 * dense_limit => Backend::Sparse,
        Backend::Auto if schur::applicable(mass, m) => Backend::Schur,
        Backend::Auto => Backend::Dense,
        other => other,
    }
}

impl SaddlePoint {
    /// Chooses the back end for a system with mass matrix `mass` (its block structure and which
    /// blocks are positive definite, at [`crate::MultibodySystem::reference_positions`];
    /// `mass_is_constant` lets the inverse blocks be computed once)
    /// and constraints `sys`, and sets it up (symbolic analysis, storage, scratch).
    pub fn new(
        backend: Backend,
        mass: &BlockDiagonal,
        mass_is_constant: bool,
        sys: &(impl ConstraintSet + ?Sized),
        dense_limit: usize,
        pivot_tolerance: f64,
    ) -> Result<Self, LinalgError> {
        Self::on_pattern(
            backend,
            mass,
            mass_is_constant,
            sys.pattern(),
            dense_limit,
            pivot_tolerance,
        )
    }

    /// As [`SaddlePoint::new`], for the constraint pattern `pattern` (a system's, or a subset of its
    /// rows).
    pub fn on_pattern(
        backend: Backend,
        mass: &BlockDiagonal,
        mass_is_constant: bool,
        pattern: &ConstraintPattern,
        dense_limit: usize,
        pivot_tolerance: f64,
    ) -> Result<Self, LinalgError> {
        let m = pattern.rows();
        let resolved = resolve(backend, mass, pattern, dense_limit);
        let dense_lu = || Some(Kind::Dense(Box::new(DenseKkt::new(mass.dim(), m, pivot_tolerance))));
        let sparse_lu = || {
            SparseKkt::new(mass, pattern, pivot_tolerance)
                .ok()
                .map(|s| Kind::Sparse(Box::new(s)))
        };
        let fallback = match (backend, resolved) {
            (Backend::Auto, Backend::SparseSchur) => sparse_lu(),
            (Backend::Auto, Backend::Tree) if mass.dim() + m > dense_limit => sparse_lu(),
            (Backend::Auto, Backend::Schur | Backend::Tree) => dense_lu(),
            _ => None,
        };
        let kind = match resolved {
            Backend::Schur if !schur::applicable(mass, m) => {
                return Err(LinalgError::Singular(
                    "the Schur back end needs mass blocks that are positive definite or diagonal".into(),
                ))
            }
            Backend::Schur => Kind::Schur(Box::new(SchurKkt::new(
                mass,
                mass_is_constant,
                pattern,
                pivot_tolerance,
            ))),
            Backend::SparseSchur => {
                if !positive_definite(mass) {
                    return Err(LinalgError::Singular(
                        "the sparse Schur back end needs every body's mass and inertia positive".into(),
                    ));
                }
                Kind::SparseSchur(Box::new(SparseSchurKkt::new(
                    mass,
                    mass_is_constant,
                    pattern,
                    pivot_tolerance,
                )?))
            }
            Backend::Tree => {
                if !positive_definite(mass) {
                    return Err(LinalgError::Singular(
                        "the tree back end needs every body's mass and inertia positive".into(),
                    ));
                }
                Kind::Tree(Box::new(TreeKkt::new(mass, pattern, pivot_tolerance).ok_or_else(
                    || {
                        LinalgError::Singular(
                            "the tree back end needs every equation on one or more distinct bodies, bodies of 3 or 6 velocities, and at most as many equations between two bodies (or a body and the ground) as a body has velocities".into(),
                        )
                    },
                )?))
            }
            Backend::Sparse => Kind::Sparse(Box::new(SparseKkt::new(mass, pattern, pivot_tolerance)?)),
            _ => Kind::Dense(Box::new(DenseKkt::new(mass.dim(), m, pivot_tolerance))),
        };
        Ok(SaddlePoint {
            kind,
            fallback,
            on_fallback: false,
        })
    }

    /// Factors `[M C_qᵀ; C_q 0]` for the current values.
    ///
    /// A Schur back end chosen by [`Backend::Auto`] hands over to the LU of the whole matrix when
    /// the Schur complement is singular or worse conditioned than [`SCHUR_FALLBACK_CONDITION`].
    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), LinalgError> {
        self.on_fallback = false;
        let primary = self.kind.factor(mass, pattern, vals);
        let ill = match &self.kind {
            Kind::Schur(s) => s.condition > SCHUR_FALLBACK_CONDITION,
            Kind::SparseSchur(s) => s.condition > SCHUR_FALLBACK_CONDITION,
            Kind::Tree(t) => t.condition > SCHUR_FALLBACK_CONDITION,
            _ => false,
        };
        match (&mut self.fallback, primary.is_err() || ill) {
            (Some(f), true) => {
                f.factor(mass, pattern, vals)?;
                self.on_fallback = true;
                Ok(())
            }
            _ => Ok(primary?),
        }
    }

    /// Solves in place: `x` holds the right-hand side `[top (n); bottom (m)]` on entry, the solution
    /// on exit.
    pub fn solve(&mut self, pattern: &ConstraintPattern, x: &mut [f64]) {
        match (&mut self.fallback, self.on_fallback) {
            (Some(f), true) => f.solve(pattern, x),
            _ => self.kind.solve(pattern, x),
        }
    }

    /// True when the last factorization is a tree factorization closing loops (its loop-closure
    /// Schur complement lost up to 4.6e-9 relative on generated mechanisms whose condition estimates
    /// stayed small: `tests/agreement.rs`, cases kept in its regressions file), or a Schur complement (not backward stable for the whole
    /// matrix: it squares the conditioning of `C_q M^-1/2`) whose condition estimate exceeds 1e3 (the
    /// estimates can fall short of the true condition number by a factor 10-100): its solution then
    /// deserves one step of iterative refinement. Below that, its forward error is already ≈ 1e-10
    /// relative.
    pub fn refines(&self) -> bool {
        const ILL_CONDITIONED: f64 = 1e3;
        if self.on_fallback {
            return false;
        }
        match &self.kind {
            Kind::Schur(s) => s.condition > ILL_CONDITIONED,
            Kind::SparseSchur(s) => s.condition > ILL_CONDITIONED,
            Kind::Tree(t) => t.condition > ILL_CONDITIONED || t.has_loops(),
            _ => false,
        }
    }

    /// Back end name: `"dense"`, `"schur"`, `"sparse"`, `"sparse-schur"` or `"tree"`.
    pub fn name(&self) -> &'static str {
        match &self.kind {
            Kind::Dense(_) => "dense",
            Kind::Schur(_) => "schur",
            Kind::Sparse(_) => "sparse",
            Kind::SparseSchur(_) => "sparse-schur",
            Kind::Tree(_) => "tree",
        }
    }
}

/// `y = K x` computed from the blocks, without the assembled matrix (for residual checks);
/// `pattern` is the pattern `vals` was evaluated on (a system's, or a subset of its rows).
pub fn kkt_mul(mass: &BlockDiagonal, pattern: &ConstraintPattern, vals: &ConstraintValues, x: &[f64], y: &mut [f64]) {
    let n = mass.dim();
    let (xt, xb) = x.split_at(n);
    let (yt, yb) = y.split_at_mut(n);
    yt.iter_mut().for_each(|v| *v = 0.0);
    yb.iter_mut().for_each(|v| *v = 0.0);
    mass.mul_add(1.0, xt, yt);
    for (&(r, c), &v) in pattern.entries().iter().zip(&vals.jacobian) {
        yt[c] += v * xb[r];
        yb[r] += v * xt[c];
    }
}

/// Largest magnitude among the entries of `M` and `C_q` (scale of the residual check).
pub fn kkt_scale(mass: &BlockDiagonal, vals: &ConstraintValues) -> f64 {
    vals.jacobian.iter().fold(mass.max_abs(), |a, v| a.max(v.abs()))
}
