//! The sparse velocity transformation (`dalembert_system::partition::VelocityTransform`) against
//! dense arithmetic on the same constraint values, and the embedding and amalgamated formulations
//! built on it against the augmented formulation on chains large enough for its sparse `C_qd` path
//! (more than `DENSE_LIMIT` dependent coordinates), planar and spatial.
//!
//! What is checked, and why the tolerances:
//! * `C_q B_i = 0` and `C_q γ_i = Q_d`, the identity on the independent rows (exactly): the
//!   definition of the transformation (`docs/equations.md` §4). The LU solves are backward stable,
//!   so the residual is a few `n ε ‖C_q‖ ‖B_i‖`: 1e-12 relative (measured ≈ 1e-15).
//! * `B_i x`, `B_iᵀ f` and `B_iᵀ M B_i` against dense products of the same `B_i`: the sparse
//!   kernels skip exact zeros only, so they differ from the dense sums by summation order:
//!   1e-13 relative.
//! * accelerations and multipliers of the three formulations: 1e-9 relative, as in
//!   `tests/agreement.rs`.

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::system::{Formulation, MultibodySystem, PartitionTracker};
use dalembert_system::partition::DENSE_LIMIT;
use dalembert_testkit::mechanisms;
use faer::Mat;
use std::sync::Arc;

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |a, x| a.max(x.abs()))
}

/// A planar chain of `n` rods with varied angles and rates.
fn planar_chain(n: usize) -> (Arc<dyn MultibodySystem>, Vec<f64>, Vec<f64>) {
    let angles: Vec<f64> = (0..n).map(|k| -0.3 - 0.05 * k as f64).collect();
    let rates: Vec<f64> = (0..n).map(|k| 0.2 * ((k % 5) as f64 - 2.0)).collect();
    let mech = mechanisms::chain(1.0, 1.0, &angles, &rates, &[]);
    (mech.model.clone(), mech.q, mech.qd)
}

/// The anchors' spatial chain of `n` links (revolute joints about alternating axes), at rest.
fn spatial_chain(n: usize) -> (Arc<dyn MultibodySystem>, Vec<f64>, Vec<f64>) {
    let model = dalembert_testkit::spatial::chain3d(n);
    let (q, v) = model.initial_state();
    (model, q, v)
}

fn check_transform(sys: &dyn MultibodySystem, q: &[f64], qd: &[f64], expect_sparse: bool) {
    let cs = sys.constraints();
    let mut values = cs.values();
    cs.evaluate(0.0, q, qd, &mut values);
    let rhs = values.gamma.clone();
    let mut tracker = PartitionTracker::new(1e3);
    let (partition, vt) = tracker.transform(0.0, cs, &values, &rhs).expect("regular C_qd");
    let (n, ni, r) = (qd.len(), partition.independent.len(), partition.rows.len());
    assert_eq!(
        r > DENSE_LIMIT,
        expect_sparse,
        "the test must exercise the intended C_qd path"
    );
    let jac = cs.jacobian_dense(&values);
    let b = Mat::from_fn(n, ni, |i, j| vt.b_row(i)[j]);
    let scale = jac.norm_max() * vt.max_abs().max(1.0);
    // C_q B_i = 0.
    let worst = (&jac * &b).norm_max();
    assert!(worst <= 1e-12 * scale, "C_q B_i = {worst:e} (scale {scale:e})");
    // Identity on the independent rows.
    for (j, &c) in partition.independent.iter().enumerate() {
        for k in 0..ni {
            assert_eq!(b[(c, k)], f64::from(j == k));
        }
    }
    // C_q γ_i = Q_d.
    let cg: Vec<f64> = (0..jac.nrows())
        .map(|i| (0..n).map(|k| jac[(i, k)] * vt.gamma[k]).sum())
        .collect();
    let g_scale = max_abs(rhs.iter().copied()).max(1.0);
    for (i, (a, e)) in cg.iter().zip(&rhs).enumerate() {
        assert!((a - e).abs() <= 1e-12 * g_scale, "row {i}: C_q γ = {a}, Q_d = {e}");
    }
    // Products against dense ones.
    let x: Vec<f64> = (0..ni).map(|j| (j as f64 * 0.37).sin()).collect();
    let f: Vec<f64> = (0..n).map(|i| (i as f64 * 0.61).cos()).collect();
    let mut bx = vec![0.0; n];
    vt.mul_add(&x, &mut bx);
    let mut btf = vec![0.0; ni];
    vt.mul_transpose(&f, &mut btf);
    for i in 0..n {
        let dense: f64 = (0..ni).map(|j| b[(i, j)] * x[j]).sum();
        assert!((bx[i] - dense).abs() <= 1e-13 * scale * ni as f64, "B x, row {i}");
    }
    for j in 0..ni {
        let dense: f64 = (0..n).map(|i| b[(i, j)] * f[i]).sum();
        assert!((btf[j] - dense).abs() <= 1e-13 * scale * n as f64, "Bᵀ f, column {j}");
    }
    // The reduced mass matrix against B_iᵀ M B_i formed densely.
    let mut mass = sys.mass_storage();
    sys.mass(q, &mut mass);
    let m_dense = Mat::from_fn(n, n, |i, j| {
        mass.entries()
            .find(|&(r, c, _)| r == i && c == j)
            .map_or(0.0, |(_, _, v)| v)
    });
    let expected = b.transpose() * &m_dense * &b;
    let mut mi = Mat::<f64>::zeros(ni, ni);
    vt.reduced_mass(&mass, &mut mi);
    let mi_scale = max_abs((0..ni).map(|j| expected[(j, j)]));
    for q in 0..ni {
        for p in q..ni {
            let (got, want) = (mi[(p, q)], expected[(p, q)]);
            assert!(
                (got - want).abs() <= 1e-13 * mi_scale * n as f64,
                "M_i[{p}, {q}] = {got}, dense {want}"
            );
        }
    }
}

#[test]
fn transform_matches_dense_arithmetic_on_both_factor_paths() {
    // Planar: 8 links (16 dependent coordinates, dense LU) and 40 (80, sparse LU).
    for (links, sparse) in [(8, false), (40, true)] {
        let (sys, q, qd) = planar_chain(links);
        check_transform(&*sys, &q, &qd, sparse);
    }
    // Spatial: revolute joints (5 equations each): 4 links dense, 16 links sparse; full inertia
    // blocks (6 × 6 with the rotational part in body axes).
    for (links, sparse) in [(4, false), (16, true)] {
        let (sys, q, v) = spatial_chain(links);
        check_transform(&*sys, &q, &v, sparse);
    }
}

#[test]
fn embedding_and_amalgamated_agree_with_augmented_on_large_chains() {
    for (sys, q, v) in [planar_chain(64), spatial_chain(24)] {
        let (n, m) = (v.len(), sys.num_equations());
        let mut reference = (vec![0.0; n], vec![0.0; m]);
        Augmented::with_defaults(sys.clone())
            .unwrap()
            .accelerations(0.0, &q, &v, None, &mut reference.0, &mut reference.1)
            .unwrap();
        let acc_scale = max_abs(reference.0.iter().copied()).max(9.81);
        let lam_scale = max_abs(reference.1.iter().copied()).max(9.81);
        let others: [Box<dyn Formulation>; 2] = [
            Box::new(Embedding::with_defaults(sys.clone())),
            Box::new(Amalgamated::with_defaults(sys.clone())),
        ];
        for mut f in others {
            let (mut a, mut l) = (vec![0.0; n], vec![0.0; m]);
            f.accelerations(0.0, &q, &v, None, &mut a, &mut l).unwrap();
            let da = max_abs(a.iter().zip(&reference.0).map(|(x, y)| x - y));
            let dl = max_abs(l.iter().zip(&reference.1).map(|(x, y)| x - y));
            assert!(da <= 1e-9 * acc_scale, "{}: accelerations differ by {da:e}", f.name());
            assert!(dl <= 1e-9 * lam_scale, "{}: multipliers differ by {dl:e}", f.name());
        }
    }
}
