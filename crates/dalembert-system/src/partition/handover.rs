//! The hand-over of coordinate partitioning at singular positions (issue 12).
//!
//! Coordinate partitioning holds the independent coordinates and solves `C_qd Δq_d = −C` for the
//! dependent ones. Near a position where `C_q` loses rank (a four-bar whose links line up, the
//! N-four-bar's windows all flat at once) **every** choice of dependent coordinates has an
//! ill-conditioned `C_qd`, and the correction, amplified by its condition number, can throw the
//! dependent coordinates onto the other branch of the mechanism. Measured on the IFToMM A02
//! N-four-bar (N = 40, RK4 h = 1 ms, `examples/n_four_bar.rs`): coordinate partitioning alone
//! ends 1.7e-3 off the exact solution at h = 1 ms and switches branch (error 2.0) at h = 0.5 ms.
//!
//! There the embedding and amalgamated formulations hand the projection over to the
//! **mass-orthogonal projection** (Bayo & Ledesma, *Nonlinear Dyn.* 9, 1996): the least change of
//! the state in the kinetic-energy metric that satisfies the constraints,
//!
//! ```text
//! [ M    C_qᵀ ] [ Δq ]   [ 0  ]                   [ M    C_qᵀ ] [ Δv ]   [ 0        ]
//! [ C_q  0    ] [ μ  ] = [ −C ]  (Newton on q),   [ C_q  0    ] [ ν  ] = [ −C_q v − C_t ]
//! ```
//!
//! which moves no coordinate more than the violation requires and so stays on the branch the
//! integrated state is on (A02, N = 40, h = 1 ms: 1.1e-7). The augmented formulation projects this
//! way at every step. The hand-over is decided per projection from the condition estimate of the
//! partition's `C_qd` after the tracker's own re-partitioning ([`super::PartitionTracker`]).

use crate::linalg::{Backend, LinalgError, SaddlePoint};
use crate::{BlockDiagonal, ConstraintError, ConstraintValues, DynamicsError, MultibodySystem};

/// Largest condition estimate of the partition's `C_qd` at which coordinate partitioning keeps the
/// projection. Measured on the A02 N-four-bar, N = 40, embedding RK4 h = 1 ms, 20 s (B₀ error):
/// without hand-over 1.7e-3; hand-over above 1e3: 1.4e-3; above 1e2: 3.7e-5; above 30: 1.1e-7
/// (279 of the 20 000 projections handed over). At 30 none of the shipped planar scenes nor a
/// chain of 64 links hands over (`dalembert simulate … --formulation embedding --stabilization
/// projection`: no hand-over in the statistics line), so away from singular positions the
/// formulations keep their own projection.
pub const HANDOVER_CONDITION: f64 = 30.0;

/// The mass-orthogonal projection the partition hands over to: the saddle-point factorization of
/// the linear-algebra layer ([`SaddlePoint`], symbolic analysis at setup) and its work vectors.
#[derive(Debug)]
pub struct MassOrthogonalProjection {
    solver: SaddlePoint,
    mass: BlockDiagonal,
    /// Right-hand side and solution, `n_v + m`.
    x: Vec<f64>,
    /// `Ċ`, `m`.
    cdot: Vec<f64>,
}

impl MassOrthogonalProjection {
    /// Sets up the factorization for `model` (allocates; nothing allocates in
    /// [`MassOrthogonalProjection::project`] after this).
    pub fn new(model: &dyn MultibodySystem) -> Result<Self, LinalgError> {
        let mut mass = model.mass_storage();
        model.mass(&model.reference_positions(), &mut mass);
        let sys = model.constraints();
        let solver = SaddlePoint::new(Backend::Auto, &mass, model.mass_is_constant(), sys, 60, 1e-13)?;
        Ok(MassOrthogonalProjection {
            solver,
            x: vec![0.0; mass.dim() + sys.num_equations()],
            cdot: vec![0.0; sys.num_equations()],
            mass,
        })
    }

    fn solve(
        &mut self,
        t: f64,
        model: &dyn MultibodySystem,
        q: &[f64],
        values: &ConstraintValues,
    ) -> Result<(), DynamicsError> {
        model.mass(q, &mut self.mass);
        let pattern = model.constraints().pattern();
        self.solver
            .factor(&self.mass, pattern, values)
            .map_err(|e| DynamicsError::Singular {
                time: t,
                what: format!("mass-orthogonal projection at a singular position: {e}"),
            })?;
        self.solver.solve(pattern, &mut self.x);
        match self.x.iter().all(|v| v.is_finite()) {
            true => Ok(()),
            false => Err(DynamicsError::Singular {
                time: t,
                what: "mass-orthogonal projection at a singular position: non-finite correction".into(),
            }),
        }
    }

    /// Projects `q` onto `C(q, t) = 0` (Newton, `‖C‖∞ ≤ tolerance`) and then `v` onto
    /// `C_q v + C_t = 0`, each the least change in the metric of `M`. `values` is scratch and ends
    /// holding the constraints at the projected state. Returns the Newton iterations.
    pub fn project(
        &mut self,
        t: f64,
        model: &dyn MultibodySystem,
        values: &mut ConstraintValues,
        q: &mut [f64],
        v: &mut [f64],
        tolerance: f64,
    ) -> Result<usize, DynamicsError> {
        const MAX_ITERATIONS: usize = 25;
        let sys = model.constraints();
        let n = v.len();
        let mut iterations = 0;
        loop {
            sys.evaluate(t, q, v, values);
            let res = values.c.iter().fold(0.0f64, |a, c| a.max(c.abs()));
            if res <= tolerance {
                break;
            }
            if iterations == MAX_ITERATIONS || !res.is_finite() {
                return Err(ConstraintError::not_converged(sys, &values.c, t, iterations, tolerance).into());
            }
            self.x[..n].iter_mut().for_each(|x| *x = 0.0);
            for (x, c) in self.x[n..].iter_mut().zip(&values.c) {
                *x = -c;
            }
            self.solve(t, model, q, values)?;
            sys.correct_positions(q, &self.x[..n]);
            iterations += 1;
        }
        sys.velocity_residual(values, v, &mut self.cdot);
        self.x[..n].iter_mut().for_each(|x| *x = 0.0);
        for (x, c) in self.x[n..].iter_mut().zip(&self.cdot) {
            *x = -c;
        }
        self.solve(t, model, q, values)?;
        v.iter_mut().zip(&self.x[..n]).for_each(|(a, d)| *a += d);
        Ok(iterations)
    }
}
