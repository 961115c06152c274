//! The reduced matrices of a scene at rest (`docs/statics.md`, (S4)–(S5)): the admissible
//! motions `B` by coordinate partitioning, `K_r`, `D_r`, `M_r` on them, and the eigenvalues of the
//! reduced stiffness relative to the reduced mass.

use super::EquilibriumError;
use dalembert_system::{ConstraintSet, MultibodySystem, Partition, ResidualTangent, TangentAt, VelocityTransform};
use nalgebra::DMatrix;

/// The reduced matrices of a scene at a state of rest: `B` (`n_v × dof`, admissible velocities
/// `v = B v_i`), `K_r = Bᵀ K B`, `D_r = Bᵀ D B`, `M_r = Bᵀ M B`, with `K = ∂r/∂q`, `D = ∂r/∂v`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Reduced {
    pub b: DMatrix<f64>,
    pub k: DMatrix<f64>,
    pub d: DMatrix<f64>,
    pub m: DMatrix<f64>,
}

/// The eigenvalues `μ` of `K_r φ = μ M_r φ` (symmetric parts; 1/s², the squares of the natural
/// angular frequencies where positive: independent of which coordinates are independent),
/// ascending, with each direction in the velocity coordinates (`B φ`). Where `M_r` is not
/// definite, those of `K_r` alone.
pub(crate) fn relative_stiffness(r: &Reduced) -> (Vec<f64>, Vec<Vec<f64>>) {
    let dof = r.k.nrows();
    if dof == 0 {
        return (Vec::new(), Vec::new());
    }
    let k = (&r.k + r.k.transpose()) * 0.5;
    let m = (&r.m + r.m.transpose()) * 0.5;
    let l_inv = m.cholesky().and_then(|c| c.l().try_inverse());
    let (a, back) = match &l_inv {
        Some(li) => (li * &k * li.transpose(), li.transpose()),
        None => (k.clone(), DMatrix::identity(dof, dof)),
    };
    let a = (&a + a.transpose()) * 0.5;
    let eig = a.symmetric_eigen();
    let mut order: Vec<usize> = (0..dof).collect();
    order.sort_by(|&x, &y| eig.eigenvalues[x].total_cmp(&eig.eigenvalues[y]));
    let values = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let shapes = order
        .iter()
        .map(|&i| {
            let phi = &back * eig.eigenvectors.column(i);
            (&r.b * phi).iter().copied().collect()
        })
        .collect();
    (values, shapes)
}

/// `B`, `K_r`, `D_r`, `M_r` at rest at `(t, q, λ)` (see [`Reduced`]): `B` from coordinate
/// partitioning, the tangent from `tangent`.
pub(crate) fn reduced_matrices(
    system: &dyn MultibodySystem,
    t: f64,
    q: &[f64],
    lambda: &[f64],
    tangent: &mut ResidualTangent,
) -> Result<Reduced, EquilibriumError> {
    reduced_on(system, t, q, lambda, tangent, None)
}

/// [`reduced_matrices`] on the admissible basis `basis` where given (any basis of the admissible
/// velocities at `q` gives the same eigenvalues, stabilities and mode shapes: `K_r`, `D_r`, `M_r`
/// change by a congruence), else coordinate partitioning's.
pub(crate) fn reduced_on(
    system: &dyn MultibodySystem,
    t: f64,
    q: &[f64],
    lambda: &[f64],
    tangent: &mut ResidualTangent,
    basis: Option<DMatrix<f64>>,
) -> Result<Reduced, EquilibriumError> {
    let sys = system.constraints();
    let n = system.layout().n_v();
    let zero = vec![0.0; n];
    let mut values = sys.values();
    sys.evaluate(t, q, &zero, &mut values);
    let b = match basis {
        Some(b) => b,
        None => admissible_basis(sys, &values)?,
    };
    let mut mass = system.mass_storage();
    let mut scratch = sys.values();
    tangent.differentiate(
        system,
        &mut mass,
        &mut scratch,
        &TangentAt {
            t,
            q,
            v: &zero,
            qdd: &zero,
            lambda,
        },
    );
    system.mass(q, &mut mass);
    let dof = b.ncols();
    // (X B) row i = Σ_j X_ij B_j for a matrix given by its entries.
    let times_b = |entries: &mut dyn Iterator<Item = (usize, usize, f64)>| {
        let mut xb = DMatrix::<f64>::zeros(n, dof);
        for (i, j, v) in entries {
            for c in 0..dof {
                xb[(i, c)] += v * b[(j, c)];
            }
        }
        b.transpose() * xb
    };
    let pattern = tangent.pattern();
    let k = times_b(&mut pattern.entries().zip(tangent.dr_dq()).map(|((i, j), &v)| (i, j, v)));
    let d = times_b(&mut pattern.entries().zip(tangent.dr_dv()).map(|((i, j), &v)| (i, j, v)));
    let m = times_b(&mut mass.entries());
    Ok(Reduced { b, k, d, m })
}

/// The admissible velocities of a spatial tree at `q` (assembled) as the joints' rates map them,
/// `v = J(q) q̇_joint` (`n × joints`, column `j` the model's velocities at a unit rate of joint
/// `j`): a basis of them with no factorization (on a chain of 64 links coordinate partitioning's
/// two full-pivot LU decompositions of the `320 × 384` Jacobian took about 20 ms). `None` where the
/// model is not a tree that joint coordinates take.
pub(crate) fn tree_basis(model: &dalembert_spatial::Model, q: &[f64], n: usize) -> Option<DMatrix<f64>> {
    let jc = model.joint_coordinates_at(q, &vec![0.0; n]).ok()?;
    let (q0, _) = jc.initial_state();
    let joints = q0.len();
    let mut frames = jc.frames();
    let (mut q_abs, mut v_abs, mut rate) = (q.to_vec(), vec![0.0; n], vec![0.0; joints]);
    let mut b = DMatrix::zeros(n, joints);
    for j in 0..joints {
        rate[j] = 1.0;
        jc.absolute(&q0, &rate, &mut frames, &mut q_abs, &mut v_abs);
        rate[j] = 0.0;
        b.column_mut(j).copy_from_slice(&v_abs);
    }
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// A basis `B` (`n × dof`) of the admissible velocities at the constraint values `values`: the
/// velocity transformation of coordinate partitioning (`docs/formulations.md`), `v = B v_i`.
fn admissible_basis(
    sys: &dyn ConstraintSet,
    values: &dalembert_system::ConstraintValues,
) -> Result<DMatrix<f64>, EquilibriumError> {
    let n = sys.num_coordinates();
    let partition = Partition::choose(sys, values, 1e-9);
    let mut transform = VelocityTransform::new(&partition, sys);
    if !transform.refactor(values) {
        return Err(EquilibriumError::Model(
            "the constraint Jacobian is singular at the equilibrium (a singular position)".into(),
        ));
    }
    transform.compute(&vec![0.0; sys.num_equations()]);
    let dof = partition.dof();
    Ok(DMatrix::from_fn(n, dof, |r, c| transform.b_row(r)[c]))
}
