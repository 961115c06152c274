//! Descent to a minimum of the potential energy in joint coordinates: the start that
//! [`crate::Scene::equilibrium`] takes first on a spatial tree whose forces at rest derive from
//! its potential (`docs/statics.md`, "Far from rest").
//!
//! In joint coordinates a tree has no constraint equations, and at rest its generalized force is
//! `Q(q) = −∇V(q)`. Each iteration solves
//!
//! ```text
//! (H + μ M) d = Q,     H = −∂Q/∂q  (central differences, symmetrized),   M the joint-space mass
//! ```
//!
//! with `μ ≥ 0` the least (doubling from a scale of `H` relative to `M`) for which `H + μ M` has
//! a Cholesky factor, so `d` always points downhill in `V`; a backtracking line search on `V`
//! (Armijo) takes `q ← q + α d`. Near a minimum `μ` falls to 0 and the steps are Newton's, so
//! the descent converges quadratically to a stable equilibrium (or one with neutral directions)
//! and never to a maximum or a saddle, which Newton's method on `Q = 0` alone may reach.
//!
//! The descent is taken only where `Q` is the potential's gradient (checked along the first
//! direction: a force that no potential gives, such as a follower torque, leaves it to the
//! relaxation) and where the tree has no joint limits; its end, mapped to the model's absolute
//! coordinates, is where Newton's method on the model's own static equations starts.

use crate::Scene;
use dalembert_system::MultibodySystem;
use nalgebra::{DMatrix, DVector};

/// The most descent iterations.
const MAX_ITERATIONS: usize = 200;
/// Converged when the largest generalized force is below this share of its scale at the start
/// (the model's own Newton iteration takes it from there to round-off).
const FORCE_TOLERANCE: f64 = 1e-9;
/// The largest change of a joint coordinate in one step (rad or m): larger steps leave the range
/// where the quadratic model of `V` is of any use.
const STEP_LIMIT: f64 = 0.5;
/// The step of the differences of `Q` and `V` (rad or m): for `H`'s forward differences a
/// truncation of `10⁻⁷` and a round-off of `10⁻¹⁶ / 10⁻⁷` relative to the stiffness, far below
/// what the descent needs (Newton's method on the model's own equations takes it to round-off).
const DIFFERENCE_STEP: f64 = 1e-7;
/// The largest relative disagreement between `−Qᵀd` and the central difference of `V` along `d`
/// for `Q` to count as the potential's gradient.
const GRADIENT_AGREEMENT: f64 = 1e-5;
/// Armijo's sufficient decrease.
const ARMIJO: f64 = 1e-4;
/// The least magnitude of a modified eigenvalue, as a share of the largest.
const FLOOR: f64 = 1e-6;

/// The model's absolute positions at the minimum of the potential the descent from the scene's
/// position reaches, or `None` where the descent does not apply (not a spatial tree in joint
/// coordinates, joint limits, forces that no potential gives) or does not converge.
pub(super) fn descend(scene: &Scene) -> Option<Vec<f64>> {
    let model = scene.model.spatial()?;
    if !scene.model.as_system().limits().is_empty() {
        return None;
    }
    let zero = vec![0.0; scene.model.as_system().layout().n_v()];
    let jc = model.joint_coordinates_at(&scene.q, &zero).ok()?;
    let system = jc.system();
    let (mut q, _) = jc.initial_state();
    let q = minimize(system.as_ref(), &mut q)?;
    let mut frames = jc.frames();
    let (mut q_abs, mut v_abs) = (scene.q.clone(), zero);
    jc.absolute(&q, &vec![0.0; q.len()], &mut frames, &mut q_abs, &mut v_abs);
    Some(q_abs)
}

/// The generalized force at rest `Q(q)` of `system` (time 0: drivers and inputs held there).
fn force(system: &dyn MultibodySystem, q: &[f64], zero: &[f64], out: &mut [f64]) -> Option<()> {
    system.applied_forces(0.0, q, zero, out);
    out.iter().all(|x| x.is_finite()).then_some(())
}

/// The descent of the module documentation from `q`, which it leaves at the minimum.
fn minimize(system: &dyn MultibodySystem, q: &mut [f64]) -> Option<Vec<f64>> {
    let n = q.len();
    if n == 0 {
        return Some(q.to_vec());
    }
    let zero = vec![0.0; n];
    let mut f = vec![0.0; n];
    let mut plus = vec![0.0; n];
    let mut mass = system.mass_storage();
    let mut stiffness = DMatrix::<f64>::zeros(n, n);
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    force(system, q, &zero, &mut f)?;
    let force_scale = 1.0 + largest(&f);
    let mut energy = system.potential_energy(0.0, q);
    let mut checked = false;
    let mut trial = vec![0.0; n];
    for _ in 0..MAX_ITERATIONS {
        if largest(&f) <= FORCE_TOLERANCE * force_scale {
            return Some(q.to_vec());
        }
        // H = −∂Q/∂q by forward differences, symmetrized.
        for j in 0..n {
            let x = q[j];
            q[j] = x + DIFFERENCE_STEP;
            force(system, q, &zero, &mut plus)?;
            q[j] = x;
            for i in 0..n {
                stiffness[(i, j)] = -(plus[i] - f[i]) / DIFFERENCE_STEP;
            }
        }
        let h = (&stiffness + stiffness.transpose()) * 0.5;
        system.mass(q, &mut mass);
        let m = DMatrix::from_row_slice(n, n, mass.block(0));
        // The regularization's unit: H's size, or the force's per unit of travel where H
        // vanishes (a chain lying horizontal), relative to M's (1/s²).
        let forces: f64 = f.iter().map(|x| x.abs()).sum();
        let unit = ((h.diagonal().abs().sum() + forces) / m.diagonal().sum()).max(f64::MIN_POSITIVE);
        let rhs = DVector::from_column_slice(&f);
        // Newton's step where H is definite; elsewhere H's eigenvalues relative to M, each
        // replaced by its magnitude (at least a share of the largest): the step then goes down
        // along a direction of negative curvature instead of up it.
        let mut d = match h.clone().cholesky() {
            Some(chol) => chol.solve(&rhs),
            None => {
                let l_inv = m.clone().cholesky()?.l().try_inverse()?;
                let a = &l_inv * &h * l_inv.transpose();
                let eig = ((&a + a.transpose()) * 0.5).symmetric_eigen();
                let floor = FLOOR * eig.eigenvalues.amax().max(unit);
                let y = eig.eigenvectors.transpose() * (&l_inv * &rhs);
                let z = y.zip_map(&eig.eigenvalues, |y, l| y / l.abs().max(floor));
                l_inv.transpose() * (&eig.eigenvectors * z)
            }
        };
        let size = d.amax();
        if !size.is_finite() {
            return None;
        }
        if size > STEP_LIMIT {
            d *= STEP_LIMIT / size;
        }
        let slope = -rhs.dot(&d);
        if !checked {
            // Is Q the potential's gradient? The central difference of V along d against −Qᵀd.
            let e = DIFFERENCE_STEP / d.amax().max(f64::MIN_POSITIVE);
            let mut along = |s: f64| {
                trial
                    .iter_mut()
                    .zip(q.iter())
                    .zip(d.iter())
                    .for_each(|((t, x), d)| *t = x + s * d);
                system.potential_energy(0.0, &trial)
            };
            let dv = (along(e) - along(-e)) / (2.0 * e);
            if (dv - slope).abs() > GRADIENT_AGREEMENT * (slope.abs() + 1e-12 * force_scale) {
                return None;
            }
            checked = true;
        }
        let mut alpha = 1.0;
        let mut stepped = false;
        for _ in 0..40 {
            trial
                .iter_mut()
                .zip(q.iter())
                .zip(d.iter())
                .for_each(|((t, x), d)| *t = x + alpha * d);
            let e = system.potential_energy(0.0, &trial);
            if e.is_finite() && e <= energy + ARMIJO * alpha * slope {
                energy = e;
                q.copy_from_slice(&trial);
                stepped = true;
                break;
            }
            alpha *= 0.5;
        }
        if !stepped {
            // No decrease of V that round-off can show: near a minimum already, where the
            // model's own Newton iteration goes on; elsewhere the descent failed.
            return (largest(&f) <= 1e-6 * force_scale).then(|| q.to_vec());
        }
        force(system, q, &zero, &mut f)?;
    }
    None
}
