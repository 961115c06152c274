//! What a formulation holds between evaluations, and the stages every formulation runs before its
//! own solve (`docs/equations.md` §2–§3): one pipeline for all of them.
//!
//! A model is immutable and shared; a run holds its work here ([`Data`]), as MuJoCo's `mjData`
//! beside `mjModel` and Pinocchio's `Data` beside `Model`. [`Data::start`] runs the stages at a
//! state `(t, q, v)`:
//!
//! 1. the lengths of the outputs checked;
//! 2. a tree in joint coordinates without constraint equations is solved outright by the
//!    articulated-body algorithm (every formulation's equations are then `M q̈ = Q`);
//! 3. otherwise the state checked, the mass matrix `M(q)` (once, when constant), the applied
//!    forces `Q(t, q, v)` checked, the constraint values `C`, `C_q`, `C_t`, `γ` (reused at an
//!    unchanged state, [`EvaluatedAt`]) checked, and the right-hand side of the acceleration
//!    equations `C_q q̈ = γ − 2α Ċ − β² C` (Baumgarte's gains when given, [`Baumgarte::apply`]).
//!
//! A formulation is the solve at the end: `[M C_qᵀ; C_q 0]` (augmented), the velocity
//! transformation (embedding), the amalgamated system.

use crate::tree::Articulated;
use crate::{Baumgarte, BlockDiagonal, ConstraintValues, DynamicsError, EvaluatedAt, MultibodySystem};

/// The evaluation data of one formulation on one model (allocated once; nothing while stepping).
#[derive(Debug, Clone)]
pub struct Data {
    /// Mass matrix `M(q)`.
    pub mass: BlockDiagonal,
    /// Applied forces `Q(t, q, v)`.
    pub q_e: Vec<f64>,
    /// Constraint values `C`, `C_q`, `C_t`, `γ` at the state.
    pub values: ConstraintValues,
    /// `Ċ = C_q v + C_t` (filled with Baumgarte's gains only).
    pub cdot: Vec<f64>,
    /// Right-hand side of the acceleration equations, `γ − 2α Ċ − β² C`.
    pub rhs: Vec<f64>,
    /// A generalized force added to `Q` ([`Data::set_extra_force`]; empty: none).
    extra: Vec<f64>,
    evaluated_at: EvaluatedAt,
    mass_loaded: bool,
    articulated: Option<Articulated>,
}

/// How far [`Data::start`] went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The tree was solved outright: `q̈` is written.
    Solved,
    /// `M`, `Q`, the constraint values and the right-hand side are loaded: the formulation solves.
    Loaded,
}

impl Data {
    /// The data of a formulation on `model`; `solve_trees`: a tree in joint coordinates without
    /// constraint equations is solved by the articulated-body algorithm ([`Stage::Solved`]).
    pub fn new(model: &dyn MultibodySystem, solve_trees: bool) -> Self {
        let (n_q, n_v, m) = (model.layout().n_q(), model.layout().n_v(), model.num_equations());
        Data {
            mass: model.mass_storage(),
            q_e: vec![0.0; n_v],
            values: model.constraints().values(),
            cdot: vec![0.0; m],
            rhs: vec![0.0; m],
            extra: Vec::new(),
            evaluated_at: EvaluatedAt::new(n_q, n_v),
            mass_loaded: false,
            articulated: if solve_trees {
                Articulated::for_system(model)
            } else {
                None
            },
        }
    }

    /// The stages before a formulation's solve at `(t, q, q̇)` (module documentation), for outputs
    /// `qdd` and `lambda` of the model's sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        &mut self,
        model: &dyn MultibodySystem,
        t: f64,
        q: &[f64],
        qd: &[f64],
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &[f64],
    ) -> Result<Stage, DynamicsError> {
        model.check_lengths(&[("q̈", qdd.len())], &[("λ", lambda.len())])?;
        if let Some(tree) = &mut self.articulated {
            tree.solve(model, (t, q, qd), &self.extra, qdd)?;
            return Ok(Stage::Solved);
        }
        self.load(model, t, q, qd)?;
        if baumgarte.is_some() {
            model.constraints().velocity_residual(&self.values, qd, &mut self.cdot);
        }
        Baumgarte::apply(baumgarte, &self.values.gamma, &self.values.c, &self.cdot, &mut self.rhs);
        Ok(Stage::Loaded)
    }

    /// `Δq̈ = M⁻¹ g` by the articulated-body algorithm at the last evaluation's state, where the
    /// tree is solved outright (`None` otherwise: the formulation solves with its factorization).
    /// A tree has no constraint equations, so no multipliers change.
    pub fn tree_response(&mut self, model: &dyn MultibodySystem, g: &[f64], dqdd: &mut [f64]) -> Option<bool> {
        let articulated = self.articulated.as_mut()?;
        let tree = model.kinematic_tree()?;
        Some(articulated.response(tree, g, dqdd))
    }

    /// The state checked, `M` (once when constant), `Q` checked, the constraint values checked.
    pub fn load(&mut self, model: &dyn MultibodySystem, t: f64, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
        model.check_state(t, q, qd)?;
        if !(self.mass_loaded && model.mass_is_constant()) {
            model.mass(q, &mut self.mass);
            self.mass_loaded = true;
        }
        model.applied_forces(t, q, qd, &mut self.q_e);
        model.check_forces(t, q, qd, &self.q_e)?;
        if !self.extra.is_empty() {
            self.q_e.iter_mut().zip(&self.extra).for_each(|(a, b)| *a += b);
        }
        self.evaluated_at
            .evaluate(model.constraints(), t, q, qd, &mut self.values);
        model.constraints().check_values(t, &self.values)
    }

    /// `C` and `Ċ` at `(t, q, q̇)` ([`crate::Formulation::residuals`]), recorded so that the next
    /// stage at the same state does not evaluate the constraints again.
    pub fn residuals(
        &mut self,
        model: &dyn MultibodySystem,
        (t, q, qd): (f64, &[f64], &[f64]),
        c: &mut [f64],
        cdot: &mut [f64],
    ) {
        self.evaluated_at
            .residuals(model.constraints(), (t, q, qd), &mut self.values, c, cdot);
    }

    /// Adds `extra` to the applied forces of the following evaluations (`None`: stops), also
    /// those of a tree solved outright by the articulated-body algorithm. Allocates only the
    /// first time. Returns true.
    pub fn set_extra_force(&mut self, extra: Option<&[f64]>) -> bool {
        match extra {
            Some(e) => {
                self.extra.resize(e.len(), 0.0);
                self.extra.copy_from_slice(e);
            }
            None => self.extra.clear(),
        }
        true
    }

    /// The constraint values were written by something else (a projection's own evaluations).
    pub fn invalidate(&mut self) {
        self.evaluated_at.invalidate();
    }
}
