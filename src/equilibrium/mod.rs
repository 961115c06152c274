//! Static equilibrium of a scene: [`Scene::equilibrium`].
//!
//! From the scene's position, Newton's method on the constrained static equations
//! (`docs/statics.md`, equations S1–S3)
//!
//! ```text
//! C_qᵀ(q) λ − Q(t, q, 0) = 0,     C(q, t) = 0,
//! ```
//!
//! with the drivers held at the scene's time 0 and the inputs at 0. Each iteration solves
//! `[K C_qᵀ; C_q 0] [Δv; Δλ] = −[r; C]`, with `K = ∂r/∂q` the tangent of the dynamic residual at
//! rest (the system's analytic tangent, or its central differences: [`ResidualTangent`]) on its
//! sparsity ([`PatternLu`]: the symbolic analysis once), and moves the positions along the
//! velocity coordinates, `q ← q ⊕ α Δv` (Euler parameters stay on the rotation group), with a
//! backtracking line search on the scaled residual.
//!
//! A singular matrix (a direction without stiffness: at the start `λ = 0` gives a pendulum none)
//! or a step that does not decrease the residual adds `μ M` to `K` (Levenberg–Marquardt with the
//! mass matrix as the metric), removed again as full steps succeed.
//!
//! On a spatial tree without joint limits whose forces at rest derive from its potential, Newton's
//! method starts where a descent of the potential in joint coordinates ends, at a minimum
//! (`src/equilibrium/descent.rs`). Elsewhere, where Newton's method from the scene's position ends at an unstable
//! equilibrium or at none, it starts again from where the scene's
//! motion with kinetic damping comes to rest ([`crate::relaxation`]): first loosely, then, while
//! it still ends unstable, more nearly at rest ([`crate::relaxation::SHARES`]).
//!
//! A joint limit the equilibrium lies beyond is held at its bound, its stop's force one more
//! multiplier, by an active set ([`Scene::equilibrium`]; `docs/statics.md`, "Joint limits").
//!
//! At the equilibrium, the reduced stiffness `K_r = Bᵀ K B` relative to the reduced mass (`B` the
//! velocity transformation of coordinate partitioning: the admissible motions) says whether it is
//! stable; a direction in which the stiffness vanishes is a neutral mechanism, reported with the
//! equilibrium. Where Newton's method cannot converge, a free direction along which a net force
//! acts is named with that force: there is no equilibrium.

use crate::output::Rows;
use crate::Scene;
use dalembert_integrators::Sample;
use dalembert_system::linalg::PatternLu;
use dalembert_system::{ResidualTangent, TangentAt};
use thiserror::Error;

mod descent;
mod held;
mod reduced;
use held::{Held, HeldRows};
pub(crate) use reduced::{reduced_matrices, relative_stiffness, Reduced};

/// Why no equilibrium was found (one line naming the cause).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EquilibriumError {
    /// A direction of the admissible motions in which nothing resists, and a net force along it:
    /// no position balances it.
    #[error("equilibrium: there is none: a net force of {} acts along {direction}, in which nothing resists (zero stiffness)", dalembert_system::Shortest(*.force))]
    Mechanism {
        /// The free direction, as its largest velocity components.
        direction: String,
        /// The net generalized force along it (per unit of the direction).
        force: f64,
    },
    /// Newton's method did not converge from the scene's position.
    #[error("equilibrium: not found from the scene's position after {iterations} iterations (residual force {force:.3e}, constraint violation {violation:.3e}); start it nearer, or look for a force that no position balances")]
    NotConverged {
        /// Iterations taken.
        iterations: usize,
        /// Largest residual generalized force at the last iterate.
        force: f64,
        /// Largest constraint violation at the last iterate.
        violation: f64,
    },
    /// The model or its constraints could not be evaluated.
    #[error("equilibrium: {0}")]
    Model(String),
}

/// Column names with their values.
type Named = Vec<(String, f64)>;

/// A static equilibrium of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// Positions at the equilibrium (the model's coordinates).
    pub q: Vec<f64>,
    /// Multipliers there.
    pub lambda: Vec<f64>,
    /// The position columns of the output (`crank.x`, …, `top.e3`) with their values.
    pub positions: Vec<(String, f64)>,
    /// The reaction and effort columns (`pin.fx`, …, `motor.effort`) with their values.
    pub reactions: Vec<(String, f64)>,
    /// Eigenvalues `μ` of the reduced stiffness relative to the reduced mass,
    /// `K_r φ = μ M_r φ` (symmetric parts), ascending, in 1/s²: the squares of the natural
    /// angular frequencies where positive, a growth rate squared where negative; they do not
    /// depend on which coordinates are independent.
    pub stiffness: Vec<f64>,
    /// The directions in which the stiffness vanishes (a neutral mechanism: a spin about a
    /// spherical joint's vertical, a slider nothing pushes), each as its largest velocity
    /// components.
    pub free_directions: Vec<String>,
    /// The directions in which the stiffness is negative: the equilibrium is unstable there.
    pub unstable_directions: Vec<String>,
    /// Whether the equilibrium is stable: every eigenvalue of the reduced stiffness positive
    /// (none free).
    pub stable: bool,
    /// Newton iterations taken.
    pub iterations: usize,
    /// The joint limits the equilibrium rests against, each held at a bound by its stop's force
    /// (the reaction column `<joint>.limit`): their names.
    pub held: Vec<String>,
    /// Each limit's force there (the system's limits; zero where free).
    pub(crate) limit_forces: Vec<f64>,
    /// The limits held, with their bounds.
    held_limits: Vec<Held>,
    /// The reduced matrices there (for the modes: computed once).
    pub(crate) reduced: Reduced,
}

/// Largest Newton iterations.
const MAX_ITERATIONS: usize = 100;
/// Converged when the constraint violation is below this (m, rad: the assembly's tolerance) …
const POSITION_TOLERANCE: f64 = 1e-12;
/// … and the residual force below this share of the force scale.
const FORCE_TOLERANCE: f64 = 1e-10;
/// Relative eigenvalue of the reduced stiffness below which a direction counts as free.
const FREE_TOLERANCE: f64 = 1e-9;
/// The largest change of a coordinate in one step, as a share of the length scale.
const STEP_LIMIT: f64 = 0.5;
/// The largest regularization, in units of the force scale per length and mass: past it the
/// residual does not decrease along any direction the matrix gives.
const MU_LARGEST: f64 = 1e8;

impl Scene {
    /// The static equilibrium where the scene comes to rest (see the module documentation):
    /// Newton's method from the scene's position, and where that ends at an unstable equilibrium
    /// or finds none, from the position where the scene's motion with kinetic damping comes to
    /// rest ([`crate::relaxation`]); against the joint limits it lies beyond, held at their
    /// bounds ([`Equilibrium::held`]).
    ///
    /// ```
    /// // A rod pinned at its end, its stops 0.5 rad either side of horizontal: it rests on the
    /// // lower one, which carries its weight's torque m g (L/2) cos 0.5.
    /// let scene = dalembert::Scene::from_toml(
    ///     r#"
    ///     [scene]
    ///     gravity = [0.0, -9.81]
    ///     [[bodies]]
    ///     name = "rod"
    ///     mass = 1.0
    ///     shape = { rod = 1.0 }
    ///     position = [0.5, 0.0]
    ///     [[joints]]
    ///     name = "pin"
    ///     type = "revolute"
    ///     bodies = ["ground", "rod"]
    ///     at = [0.0, 0.0]
    ///     limits = [-0.5, 0.5]
    ///     "#,
    ///     "rod",
    /// )?;
    /// let eq = scene.equilibrium()?;
    /// assert_eq!(eq.held, ["pin"]);
    /// let torque = eq.reactions.iter().find(|(c, _)| c == "pin.limit").map(|c| c.1);
    /// assert!((torque.unwrap() - 9.81 * 0.5 * 0.5f64.cos()).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn equilibrium(&self) -> Result<Equilibrium, EquilibriumError> {
        let mut eq = self.first_equilibrium()?;
        // Against the joint limits: the free equilibrium holds where every limit is free there;
        // otherwise the limit reached is held at its bound and the equilibrium found again, and
        // a held limit whose stop would pull lets go, until neither happens (an active set).
        let system = self.model.as_system();
        let limits = system.limits().len();
        let mut held = eq.held_limits.clone();
        for _ in 0..=2 * limits {
            let largest = (eq.lambda.iter().chain(&eq.limit_forces)).fold(0.0f64, |a, x| a.max(x.abs()));
            let tolerance = dalembert_system::friction::RELEASE_SHARE * largest;
            match held::next(system, &eq.q, &held, &eq.limit_forces, tolerance) {
                None => return Ok(eq),
                Some(next) => held = next,
            }
            eq = self.equilibrium_from(&eq.q, &held)?;
        }
        let names: Vec<&str> = held.iter().map(|h| system.limits()[h.limit].name.as_str()).collect();
        Err(EquilibriumError::Model(format!(
            "the limits of '{}' were held and let go again without settling on a set that holds (docs/statics.md, \"Joint limits\")",
            names.join("', '")
        )))
    }

    /// The equilibrium the active set of [`Scene::equilibrium`] starts from: Newton's method
    /// from the scene's position with every limit free, and where that ends unstable or at none,
    /// from where the scene's motion with kinetic damping comes to rest, with the limits it
    /// rests against held there.
    fn first_equilibrium(&self) -> Result<Equilibrium, EquilibriumError> {
        // A spatial tree whose forces at rest derive from its potential: descend to a minimum
        // in joint coordinates first, then Newton's method on the model there.
        if let Some(q) = descent::descend(self) {
            if let Ok(eq) = self.equilibrium_from(&q, &[]) {
                if eq.unstable_directions.is_empty() {
                    return Ok(eq);
                }
            }
        }
        let first = self.equilibrium_from(&self.q, &[]);
        match &first {
            Ok(eq) if eq.unstable_directions.is_empty() => return first,
            // Also where a free direction with a net force was found: it may be free only where
            // Newton's method stopped (a top lying horizontal has no stiffness along its fall).
            _ => {}
        }
        let Some(mut relaxation) = crate::relaxation::Relaxation::new(self) else {
            return first;
        };
        // Newton's method from the relaxed positions, relaxed further each time it still ends
        // at an unstable equilibrium or at none.
        let mut last = None;
        for share in crate::relaxation::SHARES {
            let Some(q) = relaxation.until(share) else { break };
            match self.equilibrium_from(&q, &held::reached(self.model.as_system(), &q)) {
                Ok(eq) if eq.unstable_directions.is_empty() => return Ok(eq),
                other => last = Some(other),
            }
        }
        match last {
            Some(Ok(eq)) if first.is_err() => Ok(eq),
            _ => first,
        }
    }

    /// Newton's method on the static equations from positions `q0` (assembled), with the limits
    /// `held` held at their bounds (their coordinates' equations `s(q) = bound` added to the
    /// independent constraint equations, their multipliers after those).
    fn equilibrium_from(&self, q0: &[f64], held: &[Held]) -> Result<Equilibrium, EquilibriumError> {
        let system = self.model.as_system();
        let sys = system.constraints();
        let (n, m) = (system.layout().n_v(), system.num_equations());
        let t = 0.0;
        // Redundant equations are left out of the Newton system (a maximal independent set keeps
        // the same positions); their multipliers are the minimum-norm ones at the end.
        let structure = self.structure().map_err(|e| EquilibriumError::Model(e.to_string()))?;
        let rows = structure.independent_rows;
        let r = rows.len();
        let a = held.len();
        let mut held_rows = HeldRows::new(system, q0, held);
        let held_entries: usize = held_rows.cols.iter().map(Vec::len).sum();
        let at_held =
            || (held_rows.cols.iter().enumerate()).flat_map(|(j, cols)| cols.iter().map(move |&c| (n + r + j, c)));
        let mut slot = vec![usize::MAX; m];
        rows.iter().enumerate().for_each(|(k, &row)| slot[row] = k);
        let mut tangent = ResidualTangent::new(system);
        let mut mass = system.mass_storage();
        system.mass(q0, &mut mass);
        // The matrix's entries: the tangent's, the mass blocks' (the regularization), `C_q`, `C_qᵀ`.
        let mut entries: Vec<(usize, usize)> = tangent.pattern().entries().collect();
        entries.extend(mass.entries().map(|(r, c, _)| (r, c)));
        let pattern = sys.pattern();
        let kept: Vec<usize> = (0..pattern.entries().len())
            .filter(|&e| slot[pattern.entries()[e].0] != usize::MAX)
            .collect();
        let at_kept = |e: &usize| (slot[pattern.entries()[*e].0], pattern.entries()[*e].1);
        entries.extend(kept.iter().map(at_kept).map(|(k, c)| (n + k, c)));
        entries.extend(at_held());
        entries.extend(kept.iter().map(at_kept).map(|(k, c)| (c, n + k)));
        entries.extend(at_held().map(|(k, c)| (c, k)));
        let mut lu = PatternLu::new(n + r + a, entries, PatternLu::DENSE_LIMIT)
            .map_err(|e| EquilibriumError::Model(e.to_string()))?;
        // `C_q`'s values on the independent rows, then the held limits' rows.
        let mut jacobian = vec![0.0; kept.len() + held_entries];
        let kept_jacobian = |values: &dalembert_system::ConstraintValues, out: &mut [f64]| {
            out.iter_mut().zip(&kept).for_each(|(o, &e)| *o = values.jacobian[e]);
        };
        let (mut values, mut scratch) = (sys.values(), sys.values());
        let (zero_v, zero_a) = (vec![0.0; n], vec![0.0; n]);
        let mut q = q0.to_vec();
        // The independent equations' multipliers, and all of them (the others 0).
        let mut lambda = vec![0.0; r + a];
        let mut full = vec![0.0; m];
        let mut f = vec![0.0; n + r + a];
        // Scales: the generalized forces at the start, the positions' size.
        let mut q_force = vec![0.0; n];
        system.applied_forces(t, &q, &zero_v, &mut q_force);
        let force_scale = 1.0 + q_force.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let length_scale = 1.0 + q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let scatter = |lambda: &[f64], full: &mut [f64]| {
            full.fill(0.0);
            rows.iter().zip(lambda).for_each(|(&row, &l)| full[row] = l);
        };
        let independent = r;
        let residual = |q: &[f64],
                        lambda: &[f64],
                        full: &mut [f64],
                        mass: &mut _,
                        values: &mut dalembert_system::ConstraintValues,
                        held_rows: &mut HeldRows,
                        f: &mut [f64]| {
            scatter(lambda, full);
            let (r, c) = f.split_at_mut(n);
            system.dynamics_residual(t, (q, &zero_v), (&zero_a, full), (mass, values), r);
            c.iter_mut().zip(&rows).for_each(|(ci, &row)| *ci = values.c[row]);
            // The held limits: their forces along their rows, their coordinates at the bounds.
            let same = held_rows.at(system, q, held, &mut c[independent..]);
            held_rows.add(&lambda[independent..], r);
            let force = r.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let violation = (values.c.iter().chain(&c[independent..])).fold(0.0f64, |a, x| a.max(x.abs()));
            let merit = r.iter().map(|x| (x / force_scale).powi(2)).sum::<f64>()
                + c.iter().map(|x| (x / length_scale).powi(2)).sum::<f64>();
            // A held limit's row that moved to other coordinates leaves the matrix's pattern.
            (force, violation, if same { merit } else { f64::INFINITY })
        };
        let mut step = vec![0.0; n + r + a];
        // The first multipliers: those of the motion at rest here, `[M C_qᵀ; C_q 0] [q̈; λ] =
        // [Q; 0]`, so that the first tangent has the constraints' geometric stiffness (with λ = 0
        // a pendulum has none).
        sys.evaluate(t, &q, &zero_v, &mut values);
        {
            kept_jacobian(&values, &mut jacobian);
            held_rows.values(&mut jacobian[kept.len()..]);
            fill(&mut lu, None, tangent.dr_dq().len(), 1.0, &mass, &jacobian);
            if lu.factor().is_ok() {
                step[..n].copy_from_slice(&q_force);
                step[n..].fill(0.0);
                lu.solve_in_place(&mut step);
                if step.iter().all(|x| x.is_finite()) {
                    lambda.copy_from_slice(&step[n..]);
                }
            }
        }
        let (mut force, mut violation, mut merit) =
            residual(&q, &lambda, &mut full, &mut mass, &mut values, &mut held_rows, &mut f);
        let (mut q_try, mut lambda_try) = (q.clone(), lambda.clone());
        let mut iterations = 0;
        // The regularization `μ M` added to `K` (1/s²): 0 while Newton's steps decrease the
        // residual, raised where the matrix is singular (a direction without stiffness: at the
        // start, λ = 0 gives a pendulum none) or a step does not decrease it, lowered again after
        // full steps (Levenberg–Marquardt with the mass matrix as the metric).
        let mu_unit = force_scale / length_scale / mass_scale(&mass);
        let mut mu = 0.0f64;
        let converged = |force: f64, violation: f64| {
            violation <= POSITION_TOLERANCE * length_scale && force <= FORCE_TOLERANCE * force_scale
        };
        // Once converged, one more full Newton step (kept where it does not increase the
        // residual) takes the last iterate from the tolerance to round-off.
        let mut polished = false;
        while !(converged(force, violation) && polished) {
            polished = converged(force, violation);
            if iterations == MAX_ITERATIONS || mu > MU_LARGEST * mu_unit {
                scatter(&lambda, &mut full);
                return Err(self.no_equilibrium(&q, &full, iterations, force, violation));
            }
            iterations += 1;
            scatter(&lambda, &mut full);
            let at = TangentAt {
                t,
                q: &q,
                v: &zero_v,
                qdd: &zero_a,
                lambda: &full,
            };
            tangent.differentiate(system, &mut mass, &mut scratch, &at);
            system.mass(&q, &mut mass);
            // `values` and the held rows hold their values at `q` (from its residual).
            kept_jacobian(&values, &mut jacobian);
            held_rows.values(&mut jacobian[kept.len()..]);
            fill(
                &mut lu,
                Some(tangent.dr_dq()),
                tangent.dr_dq().len(),
                mu,
                &mass,
                &jacobian,
            );
            let solved = lu.factor().is_ok() && {
                step.iter_mut().zip(&f).for_each(|(s, x)| *s = -x);
                lu.solve_in_place(&mut step);
                step.iter().all(|x| x.is_finite())
            };
            // Backtracking on the scaled residual.
            let mut alpha = 1.0;
            let mut accepted = false;
            let floor = if polished { 1.0 } else { 1.0 / 1024.0 };
            // A step moves no coordinate by more than `STEP_LIMIT` of the length scale (m or
            // rad): far from the equilibrium the tangent holds only nearby.
            let largest_step = step[..n].iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let limit = STEP_LIMIT * length_scale;
            if solved && largest_step > limit {
                step.iter_mut().for_each(|x| *x *= limit / largest_step);
            }
            while solved && alpha >= floor {
                q_try.copy_from_slice(&q);
                system.integrate_positions(&mut q_try, &step[..n], alpha);
                system.normalize(&mut q_try);
                for (l, (l0, d)) in lambda_try.iter_mut().zip(lambda.iter().zip(&step[n..])) {
                    *l = l0 + alpha * d;
                }
                let trial = residual(
                    &q_try,
                    &lambda_try,
                    &mut full,
                    &mut mass,
                    &mut values,
                    &mut held_rows,
                    &mut f,
                );
                let decreased = if polished {
                    trial.2 <= merit
                } else {
                    trial.2 <= (1.0 - 1e-4 * alpha) * merit
                };
                if decreased {
                    (force, violation, merit) = trial;
                    q.copy_from_slice(&q_try);
                    lambda.copy_from_slice(&lambda_try);
                    accepted = true;
                    break;
                }
                alpha *= 0.5;
            }
            if accepted {
                if alpha == 1.0 {
                    mu = if mu <= mu_unit * 1e-9 { 0.0 } else { mu * 0.1 };
                }
            } else if polished {
                // At round-off already: the polishing step is not kept.
                break;
            } else {
                // Back at (q, λ): its residual and constraint values again, and a larger μ.
                (force, violation, merit) =
                    residual(&q, &lambda, &mut full, &mut mass, &mut values, &mut held_rows, &mut f);
                mu = if mu == 0.0 { mu_unit * 1e-6 } else { mu * 10.0 };
            }
        }
        // The held limits' forces along their joints (`F = −μ`: the residual carries `+g μ`).
        let mut limit_forces = vec![0.0; system.limits().len()];
        for (h, mu) in held.iter().zip(&lambda[r..]) {
            limit_forces[h.limit] = -mu;
        }
        scatter(&lambda, &mut full);
        let held_mu = lambda[r..].to_vec();
        let mut lambda = full;
        if r < m {
            // Redundant equations: the multipliers of least norm that balance the applied forces,
            // as the minimum-norm treatment gives them in a run.
            sys.evaluate(t, &q, &zero_v, &mut values);
            system.applied_forces(t, &q, &zero_v, &mut q_force);
            // The held limits' forces act as applied ones on the constraints.
            let pushed: Vec<f64> = held_mu.iter().map(|mu| -mu).collect();
            held_rows.add(&pushed, &mut q_force);
            if let Some(l) = dalembert_system::structure::minimum_norm_multipliers(sys, &values, &q_force) {
                lambda = l;
            }
        }
        // A tree's admissible velocities are those its joints' rates give (no factorization).
        let basis = self.model.spatial().and_then(|model| reduced::tree_basis(model, &q, n));
        let mut reduced = reduced::reduced_on(system, t, &q, &lambda, &mut tangent, basis)?;
        if a > 0 {
            // A held limit keeps its joint: the admissible motions are those that keep it.
            held_rows.at(system, &q, held, &mut vec![0.0; a]);
            reduced = held::restrict(reduced, &held_rows.dense(n));
        }
        let (stiffness, shapes) = relative_stiffness(&reduced);
        // Eigenvalues (1/s²) below FREE_TOLERANCE of the largest, or of the model's own scale
        // (force per length and mass), are zero.
        let largest = stiffness.iter().fold(mu_unit, |a, x| a.max(x.abs()));
        let free = |x: f64| x.abs() <= FREE_TOLERANCE * largest;
        let names = self.model.velocity_names();
        let directions = |keep: &dyn Fn(f64) -> bool| -> Vec<String> {
            (stiffness.iter().zip(&shapes))
                .filter(|(&x, _)| keep(x))
                .map(|(_, v)| describe(&names, v))
                .collect()
        };
        let free_directions = directions(&|x| free(x));
        let unstable_directions = directions(&|x| x < 0.0 && !free(x));
        let stable = free_directions.is_empty() && unstable_directions.is_empty();
        let (positions, reactions) = self.columns_at(&q, &lambda, &limit_forces);
        let limits = system.limits();
        let held_limits = held.to_vec();
        let held = held.iter().map(|h| limits[h.limit].name.clone()).collect();
        Ok(Equilibrium {
            q,
            lambda,
            positions,
            reactions,
            stiffness,
            free_directions,
            unstable_directions,
            stable,
            iterations,
            held,
            limit_forces,
            held_limits,
            reduced,
        })
    }

    /// The position and reaction columns of an output row at rest at `(q, λ)`.
    fn columns_at(&self, q: &[f64], lambda: &[f64], limit: &[f64]) -> (Named, Named) {
        let n = self.model.num_velocities();
        let zero = vec![0.0; n];
        let mut rows = Rows::new(&self.model);
        let mut row = Vec::with_capacity(rows.names().len());
        rows.push(
            &Sample {
                t: 0.0,
                q,
                qd: &zero,
                qdd: &zero,
                lambda,
                friction: &[],
                limit,
                impact_loss: 0.0,
                work: f64::NAN,
                constraint_violation: 0.0,
                velocity_violation: 0.0,
                energy: 0.0,
            },
            &mut row,
        );
        let names = rows.names();
        let positions = (rows.state_columns(&self.model).0.into_iter())
            .map(|k| (names[k].clone(), row[k]))
            .collect();
        let reactions = rows.reaction_columns().map(|k| (names[k].clone(), row[k])).collect();
        (positions, reactions)
    }

    /// Why Newton's method stopped at `(q, λ)`: a direction without stiffness along which a net
    /// force acts (the free direction and the force), or no convergence.
    fn no_equilibrium(
        &self,
        q: &[f64],
        lambda: &[f64],
        iterations: usize,
        force: f64,
        violation: f64,
    ) -> EquilibriumError {
        let system = self.model.as_system();
        let n = system.layout().n_v();
        let mut tangent = ResidualTangent::new(system);
        let reduced = match reduced_matrices(system, 0.0, q, lambda, &mut tangent) {
            Ok(r) => r,
            Err(e) => return e,
        };
        let (stiffness, shapes) = relative_stiffness(&reduced);
        let largest = stiffness.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // The residual at rest, r = C_qᵀλ − Q: along an admissible direction the constraint
        // forces do no work, so −dᵀr is the applied force along d.
        let mut r = vec![0.0; n];
        let mut mass = system.mass_storage();
        let mut values = system.constraints().values();
        system.dynamics_residual(
            0.0,
            (q, &vec![0.0; n]),
            (&vec![0.0; n], lambda),
            (&mut mass, &mut values),
            &mut r,
        );
        let mut q_force = vec![0.0; n];
        system.applied_forces(0.0, q, &vec![0.0; n], &mut q_force);
        let scale = 1.0 + q_force.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // The free direction with the largest force along it (unit length).
        let along = stiffness
            .iter()
            .zip(&shapes)
            .filter(|(&x, _)| x.abs() <= FREE_TOLERANCE * largest || largest == 0.0 || x < 0.0)
            .map(|(_, d)| {
                let norm = d.iter().map(|x| x * x).sum::<f64>().sqrt().max(f64::MIN_POSITIVE);
                let f = -d.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>() / norm;
                (d, f)
            })
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
        match along {
            Some((d, f)) if f.abs() > 1e-8 * scale => EquilibriumError::Mechanism {
                direction: describe(
                    &self.model.velocity_names(),
                    &d.iter().map(|x| x * f.signum()).collect::<Vec<_>>(),
                ),
                force: f.abs(),
            },
            _ => EquilibriumError::NotConverged {
                iterations,
                force,
                violation,
            },
        }
    }
}

/// Writes `[K + μ M, C_qᵀ; C_q 0]` into `lu`'s values, in the order of its entries: the `nt`
/// tangent values (`None`: zero), the mass blocks times `mu`, `C_q`, `C_qᵀ`.
fn fill(
    lu: &mut PatternLu,
    tangent: Option<&[f64]>,
    nt: usize,
    mu: f64,
    mass: &dalembert_system::BlockDiagonal,
    jacobian: &[f64],
) {
    let a = lu.values_mut();
    let (k, rest) = a.split_at_mut(nt);
    match tangent {
        Some(t) => k.copy_from_slice(t),
        None => k.fill(0.0),
    }
    let (m, rest) = rest.split_at_mut(rest.len() - 2 * jacobian.len());
    for (o, (_, _, v)) in m.iter_mut().zip(mass.entries()) {
        *o = mu * v;
    }
    let (cq, cqt) = rest.split_at_mut(jacobian.len());
    cq.copy_from_slice(jacobian);
    cqt.copy_from_slice(jacobian);
}

/// The largest diagonal entry of the mass matrix (the unit of the regularization).
fn mass_scale(mass: &dalembert_system::BlockDiagonal) -> f64 {
    mass.entries()
        .filter(|(r, c, _)| r == c)
        .fold(0.0f64, |a, (_, _, v)| a.max(v.abs()))
        .max(f64::MIN_POSITIVE)
}

/// A direction over named coordinates as its largest components: `crank.angle 0.89, slider.x
/// -0.45` (normalized to a largest component of 1, at most four, those above 1 %).
pub fn describe(names: &[String], direction: &[f64]) -> String {
    let largest = direction.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if largest == 0.0 {
        return "no coordinate".into();
    }
    let mut order: Vec<usize> = (0..direction.len()).collect();
    order.sort_by(|&a, &b| direction[b].abs().total_cmp(&direction[a].abs()));
    let sign = direction[order[0]].signum();
    order
        .iter()
        .take(4)
        .filter(|&&k| direction[k].abs() > 1e-2 * largest)
        .map(|&k| format!("{} {:.3}", names[k], sign * direction[k] / largest))
        .collect::<Vec<_>>()
        .join(", ")
}
