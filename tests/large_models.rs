//! Large models take the sparse analyses (`C_q W C_qᵀ` by sparse Cholesky) and get the same answers
//! as the dense ones, computed here independently; rank-deficient models too large for the dense
//! fallback get an error naming the size, not an allocation panic.

use dalembert::constraints::{Constraint, Model, Revolute};
use dalembert::kinematics::{BodyId, BodyRef, Vec2};
use dalembert::system::ConstraintSet as _;
use dalembert::system::{ConstraintError, KinematicOptions};
use dalembert_testkit::mechanisms;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// A chain of `n` rods (1 m, 1 kg) hanging at varied angles, and its coordinates.
fn chain(n: usize) -> (Model, Vec<f64>) {
    let angles: Vec<f64> = (0..n).map(|k| -1.2 + 0.37 * ((k * 7919) % 13) as f64 / 13.0).collect();
    let m = mechanisms::chain(1.0, 1.0, &angles, &vec![0.0; n], &vec![0.0; n]);
    let model = std::sync::Arc::try_unwrap(m.model).unwrap();
    (model, m.q)
}

/// The minimum-norm solution of `A Δ = b` from the dense normal equations with a dense LU
/// (a path independent of the sparse one under test).
fn dense_min_norm(a: &Mat<f64>, b: &[f64]) -> Vec<f64> {
    let aat = a * a.transpose();
    let y = aat.partial_piv_lu().solve(&Mat::from_fn(b.len(), 1, |i, _| b[i]));
    let x = a.transpose() * y;
    (0..x.nrows()).map(|i| x[(i, 0)]).collect()
}

#[test]
fn sparse_velocity_analysis_is_the_minimum_norm_solution() {
    let (model, q) = chain(300); // 900 coordinates: above the sparse threshold
    let sys = model.constraints();
    assert!(sys.num_coordinates() >= dalembert::system::structure::SPARSE_FROM);
    let mut qd: Vec<f64> = (0..q.len()).map(|i| ((i * 31) % 17) as f64 / 17.0 - 0.5).collect();
    let qd0 = qd.clone();
    sys.solve_velocities(0.0, &q, &mut qd, &KinematicOptions::default())
        .unwrap();
    // Independent answer: Δ = Cᵀ (C Cᵀ)⁻¹ (−C_q q̇₀) (no C_t: nothing is driven).
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    let a = sys.jacobian_dense(&vals);
    let mut rhs = vec![0.0; sys.num_equations()];
    sys.jacobian_mul(&vals, &qd0, &mut rhs);
    rhs.iter_mut().for_each(|r| *r = -*r);
    let delta = dense_min_norm(&a, &rhs);
    let scale = delta.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    for i in 0..q.len() {
        // Round-off of two solvers on a system with cond(C Cᵀ) ≈ 1e5 (a 300-link chain).
        assert!((qd[i] - qd0[i] - delta[i]).abs() < 1e-9 * scale, "coordinate {i}");
    }
    let mut cdot = vec![0.0; sys.num_equations()];
    sys.jacobian_mul(&vals, &qd, &mut cdot);
    assert!(cdot.iter().all(|c| c.abs() < 1e-12), "velocities consistent");
}

#[test]
fn sparse_position_analysis_assembles_a_large_chain() {
    let (model, q) = chain(400);
    let sys = model.constraints();
    let mut q1: Vec<f64> = q
        .iter()
        .enumerate()
        .map(|(i, x)| x + 1e-3 * (((i * 13) % 7) as f64 - 3.0))
        .collect();
    let report = sys.solve_positions(0.0, &mut q1, &KinematicOptions::default()).unwrap();
    assert!(report.residual <= 1e-12 && report.iterations <= 6, "{report:?}");
}

#[test]
fn sparse_structure_analysis_matches_the_dense_rank() {
    let (model, q) = chain(300);
    let sys = model.constraints();
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    let s = sys.analyse_structure(&vals, 1e-9).unwrap();
    // A chain of N pinned rods has N degrees of freedom.
    assert_eq!((s.rank, s.degrees_of_freedom), (600, 300));
    let dense = dalembert::system::structure::column_rank(sys.jacobian_dense(&vals).transpose(), 1e-9).0;
    assert_eq!(dense, s.rank);
}

/// The chain with a second pin at the ground pivot: two redundant equations.
fn redundant_chain(n: usize) -> Model {
    let (model, q) = chain(n);
    let mut joints: Vec<Box<dyn Constraint>> = Vec::new();
    let bodies = model.bodies().to_vec();
    for k in 0..n {
        let first = if k == 0 {
            BodyRef::Ground
        } else {
            BodyRef::Body(BodyId(k - 1))
        };
        let p = dalembert::kinematics::point::global_point(
            Vec2::new(q[3 * k], q[3 * k + 1]),
            q[3 * k + 2],
            Vec2::new(-0.5, 0.0),
        );
        joints.push(Box::new(Revolute::at(
            format!("pin{k}"),
            [first, BodyRef::Body(BodyId(k))],
            p,
            &q,
        )));
    }
    joints.push(Box::new(Revolute::at(
        "again",
        [BodyRef::Ground, BodyRef::Body(BodyId(0))],
        Vec2::zeros(),
        &q,
    )));
    Model::new(bodies, vec![], joints).unwrap()
}

#[test]
fn redundant_large_models_fall_back_to_the_dense_analysis_or_say_why_not() {
    let model = redundant_chain(300);
    let sys = model.constraints();
    let (_, q) = chain(300);
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    let s = sys.analyse_structure(&vals, 1e-9).unwrap();
    assert_eq!((s.equations, s.rank, s.redundant.len()), (602, 600, 2));
    // 40 000 bodies with the same redundancy: the dense analysis would need 120 000 × 80 002
    // doubles (72 GB); the error says so instead of panicking in the allocator.
    let model = redundant_chain(40_000);
    let sys = model.constraints();
    let (_, q) = chain(40_000);
    let mut vals = sys.values();
    sys.evaluate(0.0, &q, &[], &mut vals);
    match sys.analyse_structure(&vals, 1e-9) {
        Err(e @ ConstraintError::TooLarge { .. }) => {
            assert!(
                e.to_string()
                    .starts_with("structure analysis: a dense 120000 × 80002 matrix (71.5 GiB)"),
                "{e}"
            )
        }
        other => panic!("{other:?}"),
    }
    let mut qd = vec![0.0; q.len()];
    qd[0] = 1.0;
    let err = sys
        .solve_velocities(0.0, &q, &mut qd, &KinematicOptions::default())
        .unwrap_err();
    assert!(matches!(err, ConstraintError::TooLarge { .. }), "{err}");
}

#[test]
fn dense_formulations_refuse_models_they_cannot_hold() {
    use dalembert::integrators::{IntegratorOptions, Method};
    use dalembert::{FormulationKind, Simulation, SimulationError};
    let (model, q) = chain(40_000);
    let n = q.len();
    let mut sim = Simulation {
        model: model.into(),
        q,
        qd: vec![0.0; n],
        start: 0.0,
        end: 1.0,
        formulation: FormulationKind::Embedding,
        redundancy: Default::default(),
        integrator: IntegratorOptions::fixed(Method::rk4(), 1e-3, 1e-2),
        velocity_weights: None,
        independent: None,
        coordinates: Default::default(),
        inputs: Vec::new(),
        code_forces: Vec::new(),
    };
    for kind in [FormulationKind::Embedding, FormulationKind::Amalgamated] {
        sim.formulation = kind;
        match sim.formulation() {
            Err(e @ SimulationError::Setup(_)) => assert!(
                e.to_string().ends_with("a dense 80000 × 120000 matrix (71.5 GiB) would be needed; use the augmented formulation, which is sparse"),
                "{e}"
            ),
            Err(e) => panic!("{e}"),
            Ok(_) => panic!("{} accepted a 40 000-body model", kind.name()),
        }
    }
    sim.formulation = FormulationKind::Augmented;
    assert!(sim.formulation().is_ok(), "the sparse augmented formulation takes it");
}

/// Generalized-α's iteration matrix is sparse on the system's couplings: a chain of 40 000 links
/// (120 000 coordinates, 80 000 equations) takes a step, and its positions satisfy `C = 0` to the
/// Newton tolerance (1e-10, the method's definition: the index-3 form keeps the positions on the
/// manifold).
#[test]
fn generalized_alpha_steps_a_chain_of_forty_thousand_links() {
    use dalembert::integrators::{IntegratorOptions, Method};
    use dalembert::{FormulationKind, Simulation};
    let (model, q) = chain(40_000);
    let n = q.len();
    let sim = Simulation {
        model: model.into(),
        q,
        qd: vec![0.0; n],
        start: 0.0,
        end: 2e-3,
        formulation: FormulationKind::Augmented,
        redundancy: Default::default(),
        integrator: IntegratorOptions::fixed(Method::generalized_alpha(0.8), 1e-3, 1e-3),
        velocity_weights: None,
        independent: None,
        coordinates: Default::default(),
        inputs: Vec::new(),
        code_forces: Vec::new(),
    };
    let stats = sim.run(&mut |_| {}).unwrap();
    assert_eq!(stats.steps, 2);
    assert!(
        stats.max_constraint_violation <= 1e-10,
        "{}",
        stats.max_constraint_violation
    );
}
