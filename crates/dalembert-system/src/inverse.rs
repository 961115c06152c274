//! Inverse dynamics of kinematically driven systems (`docs/equations.md` §7).
//!
//! When drivers fix every degree of freedom (`rank C_q = n`), position, velocity and acceleration
//! analysis give `q, v, v̇` from the constraints alone, and `C_qᵀ λ = Q − M v̇` gives the
//! multipliers, hence every joint reaction and every driver effort (`−λ`), which the system's
//! modelling crate reads from them (e.g. `dalembert_constraints::ConstraintSystem::reactions`).

use crate::{DynamicsError, KinematicOptions, MultibodySystem};
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::sync::Arc;

/// The motion and forces of a driven system at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseSolution {
    /// Time.
    pub time: f64,
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities.
    pub qd: Vec<f64>,
    /// Accelerations.
    pub qdd: Vec<f64>,
    /// Multipliers.
    pub lambda: Vec<f64>,
}

/// Inverse dynamics of a fully driven model.
#[derive(Debug)]
pub struct InverseDynamics {
    model: Arc<dyn MultibodySystem>,
    options: KinematicOptions,
}

impl InverseDynamics {
    /// Checks that the model is fully driven at configuration `q` (approximate is fine: it is
    /// assembled first) and prepares the solver.
    pub fn new(model: Arc<dyn MultibodySystem>, q: &[f64], options: KinematicOptions) -> Result<Self, DynamicsError> {
        let sys = model.constraints();
        let mut q = q.to_vec();
        sys.solve_positions(0.0, &mut q, &options)?;
        let mut vals = sys.values();
        sys.evaluate(0.0, &q, &[], &mut vals);
        let s = sys.analyse_structure(&vals, options.rank_tolerance)?;
        if s.degrees_of_freedom != 0 {
            return Err(DynamicsError::Singular {
                time: 0.0,
                what: format!(
                    "inverse dynamics needs a fully driven model; {} degrees of freedom are free",
                    s.degrees_of_freedom
                ),
            });
        }
        if !s.is_full_rank() {
            return Err(DynamicsError::RedundantConstraints {
                time: 0.0,
                rank: s.rank,
                equations: s.equations,
                involved: s.redundant,
            });
        }
        Ok(InverseDynamics { model, options })
    }

    /// Solves at time `t`, starting position analysis from `q_guess`. Between two instants use
    /// [`InverseDynamics::advance`], which follows the motion on its branch.
    pub fn solve(&self, t: f64, q_guess: &[f64]) -> Result<InverseSolution, DynamicsError> {
        let n = self.model.layout().n_v();
        let mut q = q_guess.to_vec();
        self.model.constraints().solve_positions(t, &mut q, &self.options)?;
        self.complete(t, q, vec![0.0; n], vec![0.0; n])
    }

    /// The solution at `t` reached from `from` by continuation, so that it stays on the branch of
    /// the motion `from` lies on (position analysis from a far guess may converge to another
    /// assembly; at a change point, where two branches cross, the positions alone do not decide).
    ///
    /// Substeps `δ` with `δ ‖v‖∞ ≤ 0.1` (m or rad): positions predicted by `q ⊕ (δ v + δ²/2 v̇)`,
    /// then corrected by minimum-norm Newton ([`crate::kinematics::solve_positions`]); a substep
    /// whose correction is not small against the predicted motion (> 1 %) is halved. Velocities
    /// and accelerations are the least change from `v + δ v̇` and `v̇` that satisfies the velocity
    /// and acceleration equations: unique where `C_q` has full rank, and on a singular instant (a
    /// change point, where `C_q` loses rank) the prediction supplies the part the equations leave
    /// free, so the motion keeps its smooth branch.
    pub fn advance(&self, from: &InverseSolution, t: f64) -> Result<InverseSolution, DynamicsError> {
        let model = &self.model;
        let sys = model.constraints();
        let inf = |x: &[f64]| x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut cur = from.clone();
        let mut halvings = 0;
        while cur.time < t {
            let speed = inf(&cur.qd);
            let mut dt = (t - cur.time).min(0.1 / speed.max(1e-12));
            dt /= f64::powi(2.0, halvings);
            let t1 = if dt >= t - cur.time { t } else { cur.time + dt };
            let dt = t1 - cur.time;
            let mut q = cur.q.clone();
            let w: Vec<f64> = cur.qd.iter().zip(&cur.qdd).map(|(v, a)| v + 0.5 * dt * a).collect();
            model.integrate_positions(&mut q, &w, dt);
            model.normalize(&mut q);
            let predicted = q.clone();
            let ok = sys.solve_positions(t1, &mut q, &self.options).is_ok() && {
                let moved = q.iter().zip(&predicted).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                moved <= 0.01 * dt * speed + 1e-9
            };
            if !ok {
                halvings += 1;
                if halvings > 30 {
                    // Let position analysis report why, from the last point reached.
                    let mut q = cur.q.clone();
                    sys.solve_positions(t1, &mut q, &self.options)?;
                    return Err(DynamicsError::Singular {
                        time: t1,
                        what: "the motion cannot be followed on its branch (position analysis needs a step below 1e-9 of the interval)".into(),
                    });
                }
                continue;
            }
            halvings = halvings.saturating_sub(1);
            let qd: Vec<f64> = cur.qd.iter().zip(&cur.qdd).map(|(v, a)| v + dt * a).collect();
            let qdd = cur.qdd.clone();
            cur = self.complete(t1, q, qd, qdd)?;
        }
        Ok(cur)
    }

    /// Velocities and accelerations (least change from the guesses), then the multipliers.
    fn complete(
        &self,
        t: f64,
        q: Vec<f64>,
        mut qd: Vec<f64>,
        mut qdd: Vec<f64>,
    ) -> Result<InverseSolution, DynamicsError> {
        let model = &self.model;
        let sys = model.constraints();
        let n = model.layout().n_v();
        sys.solve_velocities(t, &q, &mut qd, &self.options)?;
        sys.solve_accelerations(t, &q, &qd, &mut qdd, &self.options)?;
        // C_qᵀ λ = Q_e − M q̈ (square, n × n).
        let mut rhs = vec![0.0; n];
        model.applied_forces(t, &q, &qd, &mut rhs);
        let mut mass = model.mass_storage();
        model.mass(&q, &mut mass);
        mass.mul_add(-1.0, &qdd, &mut rhs);
        let mut vals = sys.values();
        sys.evaluate(t, &q, &qd, &mut vals);
        let jt = sys.jacobian_dense(&vals).transpose().to_owned();
        // Within a relative pivot of SINGULAR_INSTANT of rank loss the reactions, which grow as
        // 1/|t − t*| around a singular position, exceed a million times their regular size and the
        // solve's error is amplified as much: the instant counts as singular.
        const SINGULAR_INSTANT: f64 = 1e-6;
        let (rank, _) = crate::structure::column_rank(jt.as_ref(), SINGULAR_INSTANT.max(self.options.rank_tolerance));
        if rank < n {
            return Err(DynamicsError::Singular {
                time: t,
                what: format!(
                    "the mechanism is at a singular position (constraint Jacobian rank {rank} of {n}, links lined up): the joint reactions are unbounded at this instant (around it they grow as 1/|t - t*|), so none are reported; choose output times that avoid it (equations involved: {})",
                    crate::error::list(&sys.dependent_equations(&vals, SINGULAR_INSTANT))
                ),
            });
        }
        let b = Mat::from_fn(n, 1, |i, _| rhs[i]);
        let lam = jt.partial_piv_lu().solve(&b);
        let lambda: Vec<f64> = (0..n).map(|i| lam[(i, 0)]).collect();
        if lambda.iter().any(|v| !v.is_finite()) {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: "multipliers (driven system singular here)".into(),
            });
        }
        Ok(InverseSolution {
            time: t,
            q,
            qd,
            qdd,
            lambda,
        })
    }
}
