//! Dense and sparse back ends agree; singular systems are reported, or solved in the minimum-norm
//! sense when asked.

use dalembert_augmented::{Augmented, AugmentedOptions, Backend};
use dalembert_constraints::{Constraint, Model, Revolute};
use dalembert_kinematics::{Body, BodyId, BodyRef, Gravity, Vec2};
use dalembert_system::{ConstraintSet as _, MultibodySystem as _};
use dalembert_system::{DynamicsError, Formulation, RedundancyTreatment};
use dalembert_testkit::mechanisms;
use std::sync::Arc;

fn run(model: &Arc<Model>, q: &[f64], qd: &[f64], backend: Backend) -> (Vec<f64>, Vec<f64>) {
    let mut f = Augmented::new(
        model.clone(),
        AugmentedOptions {
            backend,
            ..Default::default()
        },
    )
    .unwrap();
    let expected = match backend {
        Backend::Dense => "dense",
        Backend::Schur => "schur",
        Backend::SparseSchur => "sparse-schur",
        _ => "sparse",
    };
    assert_eq!(f.backend_name(), expected);
    let (mut qdd, mut lam) = (vec![0.0; q.len()], vec![0.0; model.num_equations()]);
    f.accelerations(0.3, q, qd, None, &mut qdd, &mut lam).unwrap();
    (qdd, lam)
}

/// Chains of 1 to 500 rods in a zig-zag, moving: q̈ and λ from both back ends agree to
/// 1e-9 relative to the largest entry (the condition number of a 500-link chain's saddle-point
/// matrix reaches ≈ 1e5, so round-off differences up to ≈ 1e-11 are expected).
#[test]
fn dense_and_sparse_agree_on_chains() {
    for &n in &[1usize, 2, 5, 20, 100, 500] {
        let angles: Vec<f64> = (0..n).map(|k| -1.2 + 0.7 * ((k * 7 % 11) as f64 / 11.0)).collect();
        let rates: Vec<f64> = (0..n).map(|k| 0.5 - ((k * 3 % 5) as f64) / 5.0).collect();
        let mech = mechanisms::chain(1.0, 1.0, &angles, &rates, &[]);
        let (a1, l1) = run(&mech.model, &mech.q, &mech.qd, Backend::Dense);
        let (a2, l2) = run(&mech.model, &mech.q, &mech.qd, Backend::Sparse);
        // The Schur back ends (dense and sparse) against the dense LU.
        for backend in [Backend::Schur, Backend::SparseSchur] {
            let (a, l) = run(&mech.model, &mech.q, &mech.qd, backend);
            let da = a1.iter().zip(&a).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            let dl = l1.iter().zip(&l).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            let sa = a1.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            let sl = l1.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            assert!(
                da <= 1e-9 * sa && dl <= 1e-9 * sl,
                "n = {n}, {backend:?}: Δq̈ {da:e}, Δλ {dl:e}"
            );
        }
        let (a3, l3) = run(&mech.model, &mech.q, &mech.qd, Backend::SparseSchur);
        let (a4, l4) = run(&mech.model, &mech.q, &mech.qd, Backend::Schur);
        for (a, l) in [(&a3, &l3), (&a4, &l4)] {
            let da = a1.iter().zip(a).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            let dl = l1.iter().zip(l).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            let sa = a1.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            let sl = l1.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            assert!(
                da <= 1e-9 * sa && dl <= 1e-9 * sl,
                "n = {n}: Schur Δq̈ {da:e}, Δλ {dl:e}"
            );
        }
        let sa = a1.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let sl = l1.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        let da = a1.iter().zip(&a2).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        let dl = l1.iter().zip(&l2).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(
            da <= 1e-9 * sa && dl <= 1e-9 * sl,
            "n = {n}: Δq̈ {da:e} (scale {sa:e}), Δλ {dl:e} (scale {sl:e})"
        );
    }
}

/// A parallelogram with a redundant third crank (see `dalembert-constraints` tests).
fn parallelogram(phi: f64) -> (Arc<Model>, Vec<f64>, Vec<f64>) {
    let u = Vec2::new(phi.cos(), phi.sin());
    let w = 1.5; // all cranks turn at the same rate
    let v = Vec2::new(-phi.sin(), phi.cos()) * w;
    let q = vec![
        u.x / 2.0,
        u.y / 2.0,
        phi,
        1.0 + u.x,
        u.y,
        0.0,
        2.0 + u.x / 2.0,
        u.y / 2.0,
        phi,
        1.0 + u.x / 2.0,
        u.y / 2.0,
        phi,
    ];
    let qd = vec![
        v.x / 2.0,
        v.y / 2.0,
        w,
        v.x,
        v.y,
        0.0,
        v.x / 2.0,
        v.y / 2.0,
        w,
        v.x / 2.0,
        v.y / 2.0,
        w,
    ];
    let b = |i| BodyRef::Body(BodyId(i));
    let g = BodyRef::Ground;
    let joints: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::at("A", [g, b(0)], Vec2::zeros(), &q)),
        Box::new(Revolute::at("B", [b(0), b(1)], u, &q)),
        Box::new(Revolute::at("C", [b(1), b(2)], Vec2::new(2.0, 0.0) + u, &q)),
        Box::new(Revolute::at("D", [g, b(2)], Vec2::new(2.0, 0.0), &q)),
        Box::new(Revolute::at("E", [g, b(3)], Vec2::new(1.0, 0.0), &q)),
        Box::new(Revolute::at("F", [b(3), b(1)], Vec2::new(1.0, 0.0) + u, &q)),
    ];
    let bodies = vec![
        Body::rod("crank1", 1.0, 1.0).unwrap(),
        Body::rod("coupler", 2.0, 2.0).unwrap(),
        Body::rod("crank2", 1.0, 1.0).unwrap(),
        Body::rod("crank3", 1.0, 1.0).unwrap(),
    ];
    let model = Model::new(bodies, vec![Box::new(Gravity::new(Vec2::new(0.0, -9.81)))], joints).unwrap();
    (Arc::new(model), q, qd)
}

#[test]
fn redundant_constraints_are_an_error_naming_the_joints() {
    let (model, q, qd) = parallelogram(1.0);
    for backend in [Backend::Dense, Backend::Sparse, Backend::Schur, Backend::SparseSchur] {
        let mut f = Augmented::new(
            model.clone(),
            AugmentedOptions {
                backend,
                ..Default::default()
            },
        )
        .unwrap();
        let (mut qdd, mut lam) = (vec![0.0; 12], vec![0.0; 12]);
        let err = f.accelerations(0.7, &q, &qd, None, &mut qdd, &mut lam).unwrap_err();
        match &err {
            DynamicsError::RedundantConstraints {
                time,
                rank,
                equations,
                involved,
            } => {
                assert_eq!((*time, *rank, *equations), (0.7, 11, 12));
                // The self-stress of a parallelogram loads all six pins' horizontal equations.
                assert!(involved.len() >= 3, "{involved:?}");
            }
            other => panic!("{backend:?}: expected redundancy error, got {other}"),
        }
    }
}

/// With the minimum-norm treatment the motion is still the parallelogram's: one equation in the
/// crank angle φ, `(Σ J_k) φ̈ = −g (Σ m_k L_k/2 + m_coupler L) cos φ` for rods pinned at one end
/// (J_k = m L²/3 about the pivot) plus the translating coupler (m_c L² about nothing: it translates).
/// The reactions satisfy `C_qᵀ λ = Q_e − M q̈` and λ is the minimum-norm one.
#[test]
fn minimum_norm_treatment_gives_the_parallelogram_motion() {
    let phi = 1.0;
    let (model, q, qd) = parallelogram(phi);
    let opts = AugmentedOptions {
        redundancy: RedundancyTreatment::MinimumNorm,
        ..Default::default()
    };
    let mut f = Augmented::new(model.clone(), opts).unwrap();
    let (mut qdd, mut lam) = (vec![0.0; 12], vec![0.0; 12]);
    f.accelerations(0.0, &q, &qd, None, &mut qdd, &mut lam).unwrap();
    // Closed form: three cranks (1 kg, 1 m) and a translating coupler (2 kg) whose centre moves on a
    // circle of radius 1: inertia 3·(1/3) + 2·1² = 3, gravity moment g (3·0.5 + 2·1) cos φ.
    let alpha = -9.81 * (3.0 * 0.5 + 2.0) * phi.cos() / 3.0;
    for k in [2, 8, 11] {
        assert!((qdd[k] - alpha).abs() < 1e-10 * 9.81, "crank α {} vs {alpha}", qdd[k]);
    }
    assert!(qdd[5].abs() < 1e-10);
    // Equilibrium of every body: C_qᵀ λ = Q_e − M q̈.
    let sys = model.constraints();
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &qd, &mut vals);
    let mut lhs = vec![0.0; 12];
    sys.jacobian_transpose_mul_add(&vals, 1.0, &lam, &mut lhs);
    let mut rhs = vec![0.0; 12];
    model.applied_forces(0.0, &q, &qd, &mut rhs);
    model.mass_matrix(&q).mul_add(-1.0, &qdd, &mut rhs);
    for i in 0..12 {
        assert!(
            (lhs[i] - rhs[i]).abs() < 1e-9 * 30.0,
            "row {i}: {} vs {}",
            lhs[i],
            rhs[i]
        );
    }
    // Minimum norm: λ has no component in the left null space of C_q (the self-stress mode).
    let jac = sys.jacobian_dense(&vals);
    let svd = jac.svd().unwrap();
    let u = svd.U();
    let null_col = 11; // smallest singular value last
    let proj: f64 = (0..12).map(|i| u[(i, null_col)] * lam[i]).sum();
    assert!(proj.abs() < 1e-9 * 30.0, "λ has a self-stress component {proj}");
}

#[test]
fn massless_free_body_is_reported_by_name() {
    // A massless, inertia-free rod pinned to the ground: nothing determines its motion.
    let q = vec![0.5, 0.0, 0.0];
    let model = Model::new(
        vec![Body::new("ghost", 0.0, 0.0).unwrap()],
        vec![],
        vec![Box::new(Revolute::at(
            "pin",
            [BodyRef::Ground, BodyRef::Body(BodyId(0))],
            Vec2::zeros(),
            &q,
        ))],
    )
    .unwrap();
    let mut f = Augmented::with_defaults(Arc::new(model)).unwrap();
    let (mut qdd, mut lam) = (vec![0.0; 3], vec![0.0; 2]);
    let err = f
        .accelerations(1.5, &q, &[0.0; 3], None, &mut qdd, &mut lam)
        .unwrap_err();
    assert!(
        matches!(&err, DynamicsError::SingularMass { time, bodies } if *time == 1.5 && bodies == &["ghost"]),
        "{err}"
    );
}

#[test]
fn non_finite_state_is_an_error_naming_the_body() {
    let mech = mechanisms::chain(1.0, 1.0, &[0.1, 0.2], &[0.0, 0.0], &[]);
    let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
    let mut q = mech.q.clone();
    q[4] = f64::NAN;
    let (mut qdd, mut lam) = (vec![0.0; 6], vec![0.0; 4]);
    let err = f
        .accelerations(0.0, &q, &mech.qd, None, &mut qdd, &mut lam)
        .unwrap_err();
    assert!(err.to_string().contains("link1"), "{err}");
}

/// Projection puts a perturbed state back on the manifold: |C| ≤ tolerance, |Ċ| at round-off.
#[test]
fn projection_restores_the_constraints() {
    let mech = mechanisms::four_bar(2.0, 1.0, 0.0, false);
    let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
    let mut q: Vec<f64> = mech
        .q
        .iter()
        .enumerate()
        .map(|(i, x)| x + 1e-3 * ((i % 3) as f64 - 1.0))
        .collect();
    let mut qd: Vec<f64> = mech.qd.iter().map(|v| v + 0.01).collect();
    let it = f.project(0.0, &mut q, &mut qd, 1e-12).unwrap();
    assert!((1..=6).contains(&it), "Newton iterations {it}");
    let (mut c, mut cd) = (vec![0.0; 8], vec![0.0; 8]);
    f.residuals(0.0, &q, &qd, &mut c, &mut cd);
    assert!(
        c.iter().all(|x| x.abs() <= 1e-12) && cd.iter().all(|x| x.abs() <= 1e-12),
        "{c:?} {cd:?}"
    );
}
