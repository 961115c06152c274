//! The tree recursions checked against each other and against independent quantities, on a
//! branched tree with revolute and prismatic joints, rotated joint frames, offset centres of mass,
//! full inertia tensors and joint spring–damper–actuators:
//!
//! * the articulated-body algorithm's `q̈` solves `M q̈ = Q` with `M` from the composite-rigid-body
//!   algorithm and `Q` from the recursive Newton–Euler algorithm (two other recursions; a dense
//!   LU here). Tolerance 1e-11 of the largest `|q̈|`: the residual of two O(n) recursions and a
//!   dense LU of a 6 × 6 matrix of condition below 1e4 at round-off;
//! * `½ q̇ᵀ M q̇` equals the kinetic energy summed body by body, to 1e-13 relative;
//! * at rest, `Q = −∂V/∂q` (gravity and springs), `V` differenced centrally with step 1e-6: the
//!   truncation error is O(h²) ≈ 1e-12 times the third derivative, so 1e-8 absolute on forces of
//!   order 10;
//! * `M` is symmetric positive definite (Cholesky succeeds) and symmetric to round-off.

use dalembert_system::tree::{Articulated, JointForce, JointKind, KinematicTree, TreeBody};
use dalembert_system::{JointSpace, MultibodySystem};
use faer::prelude::Solve;

const I3: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Rotation by `angle` about the unit `axis` (rows).
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

#[allow(clippy::too_many_arguments)]
fn body(
    name: &str,
    parent: Option<usize>,
    kind: JointKind,
    axis: [f64; 3],
    location: [f64; 3],
    rot: [[f64; 3]; 3],
    mass: f64,
    com: [f64; 3],
    force: Option<JointForce>,
) -> TreeBody {
    TreeBody {
        name: name.into(),
        parent,
        kind,
        axis,
        location,
        rotation: rot,
        mass,
        com,
        // Principal moments ≈ 0.049, 0.071, 0.080 (times the mass): a rigid body's.
        inertia: [[0.08, 0.005, -0.004], [0.005, 0.07, 0.002], [-0.004, 0.002, 0.05]].map(|r| r.map(|x| x * mass)),
        force,
    }
}

/// A branched tree: a base turning about a tilted axis, an arm on it, a slider along the arm, and
/// a second branch from the base; gravity along −z.
fn branched() -> KinematicTree {
    use JointKind::{Prismatic, Revolute};
    let spring = JointForce {
        stiffness: 30.0,
        damping: 0.0,
        rest: 0.2,
        effort: 1.5,
    };
    let bodies = vec![
        body(
            "base",
            None,
            Revolute,
            [0.2, 0.1, 1.0],
            [0.0, 0.0, 0.3],
            rotation([1.0, 2.0, 0.5], 0.4),
            2.0,
            [0.1, 0.0, 0.2],
            None,
        ),
        body(
            "arm",
            Some(0),
            Revolute,
            [0.0, 1.0, 0.0],
            [0.3, 0.1, 0.4],
            rotation([0.0, 0.0, 1.0], 0.7),
            1.2,
            [0.4, 0.05, 0.0],
            Some(spring),
        ),
        body(
            "slider",
            Some(1),
            Prismatic,
            [1.0, 0.0, 0.1],
            [0.8, 0.0, 0.0],
            I3,
            0.6,
            [0.0, 0.02, -0.03],
            Some(JointForce {
                stiffness: 80.0,
                damping: 0.0,
                rest: 0.0,
                effort: -2.0,
            }),
        ),
        body(
            "branch",
            Some(0),
            Revolute,
            [1.0, 0.0, 0.0],
            [-0.2, 0.3, 0.1],
            rotation([0.3, -1.0, 0.2], -1.1),
            0.9,
            [0.0, 0.35, 0.1],
            None,
        ),
        body(
            "tip",
            Some(3),
            Revolute,
            [0.0, 0.0, 1.0],
            [0.0, 0.7, 0.0],
            I3,
            0.4,
            [0.2, 0.0, 0.0],
            None,
        ),
    ];
    KinematicTree::new([0.0, 0.0, -9.81], bodies).expect("the branched tree is well formed")
}

fn states() -> Vec<(Vec<f64>, Vec<f64>)> {
    vec![
        (vec![0.0; 5], vec![0.0; 5]),
        (vec![0.3, -0.8, 0.15, 1.2, -0.4], vec![1.5, -2.0, 0.7, 0.3, 3.1]),
        (vec![-1.9, 2.4, -0.3, -0.6, 2.9], vec![-0.9, 0.4, -1.2, 2.5, -1.7]),
    ]
}

/// `M` (row-major) and `Q` of the system at `(q, q̇)`.
fn mass_and_forces(sys: &JointSpace, q: &[f64], qd: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut m = sys.mass_storage();
    sys.mass(q, &mut m);
    let mut f = vec![0.0; q.len()];
    sys.applied_forces(0.0, q, qd, &mut f);
    (m.block(0).to_vec(), f)
}

fn solve_dense(n: usize, m: &[f64], b: &[f64]) -> Vec<f64> {
    let a = faer::Mat::from_fn(n, n, |i, j| m[i * n + j]);
    let rhs = faer::Mat::from_fn(n, 1, |i, _| b[i]);
    let x = a.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| x[(i, 0)]).collect()
}

/// The largest `|got − expected|` and the largest `|expected|`.
fn gap(got: &[f64], expected: &[f64]) -> (f64, f64) {
    let scale = expected.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let diff = got.iter().zip(expected).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    (diff, scale)
}

#[test]
fn articulated_body_solves_the_composite_inertia_and_newton_euler_equations() {
    let tree = branched();
    let sys = JointSpace::new(tree.clone());
    let mut aba = Articulated::new(&tree);
    let n = tree.len();
    for (q, qd) in states() {
        let (m, f) = mass_and_forces(&sys, &q, &qd);
        let expected = solve_dense(n, &m, &f);
        let mut qdd = vec![0.0; n];
        aba.solve(&sys, (0.0, &q, &qd), &[], &mut qdd)
            .expect("the tree has inertia on every joint");
        let (diff, scale) = gap(&qdd, &expected);
        assert!(diff <= 1e-11 * scale, "q = {q:?}: |Δq̈| {diff:e} of {scale:e}");
    }
}

/// The response `M⁻¹ g` from the last solve's articulated inertias (what an impact at a joint
/// limit and joint friction ask of a tree solved outright) against `M` formed by the composite
/// rigid bodies (`mass_and_forces`) and solved densely: 1e-11 of the largest entry (the two are
/// independent O(n) and O(n³) computations of the same solve, round-off of order 1e-15 on a tree
/// of five bodies). None before any solve.
#[test]
fn articulated_response_is_the_inverse_mass_matrix_applied_to_a_force() {
    let tree = branched();
    let sys = JointSpace::new(tree.clone());
    let mut aba = Articulated::new(&tree);
    let n = tree.len();
    let mut x = vec![0.0; n];
    assert!(!aba.response(&tree, &[1.0; 5], &mut x), "no solve made yet");
    for (k, (q, qd)) in states().into_iter().enumerate() {
        let (m, _) = mass_and_forces(&sys, &q, &qd);
        let mut qdd = vec![0.0; n];
        aba.solve(&sys, (0.0, &q, &qd), &[], &mut qdd)
            .expect("the tree has inertia on every joint");
        let g: Vec<f64> = (0..n).map(|i| ((i + k) as f64 * 1.3).sin() + 0.2).collect();
        let expected = solve_dense(n, &m, &g);
        assert!(aba.response(&tree, &g, &mut x));
        let (diff, scale) = gap(&x, &expected);
        assert!(diff <= 1e-11 * scale, "q = {q:?}: |Δx| {diff:e} of {scale:e}");
    }
}

#[test]
fn mass_matrix_gives_the_kinetic_energy_and_is_symmetric_positive_definite() {
    let tree = branched();
    let sys = JointSpace::new(tree.clone());
    let n = tree.len();
    for (q, qd) in states().into_iter().skip(1) {
        let (m, _) = mass_and_forces(&sys, &q, &qd);
        let quadratic: f64 = (0..n)
            .map(|i| (0..n).map(|j| qd[i] * m[i * n + j] * qd[j]).sum::<f64>())
            .sum();
        let t = sys.kinetic_energy(&q, &qd);
        assert!(
            (0.5 * quadratic - t).abs() <= 1e-13 * t,
            "½ q̇ᵀMq̇ {} against T {t}",
            0.5 * quadratic
        );
        let mat = faer::Mat::from_fn(n, n, |i, j| m[i * n + j]);
        assert!(
            (0..n).all(|i| (0..n).all(|j| (m[i * n + j] - m[j * n + i]).abs() <= 1e-15 * m[i * n + i].abs().max(1.0)))
        );
        assert!(
            mat.llt(faer::Side::Lower).is_ok(),
            "M is not positive definite at q = {q:?}"
        );
    }
}

#[test]
fn forces_at_rest_are_minus_the_gradient_of_the_potential() {
    let tree = branched();
    let sys = JointSpace::new(tree.clone());
    let n = tree.len();
    let h = 1e-6;
    for (q, _) in states() {
        let (_, f) = mass_and_forces(&sys, &q, &vec![0.0; n]);
        for i in 0..n {
            let (mut up, mut down) = (q.clone(), q.clone());
            up[i] += h;
            down[i] -= h;
            let grad = (sys.potential_energy(0.0, &up) - sys.potential_energy(0.0, &down)) / (2.0 * h);
            assert!(
                (f[i] + grad).abs() < 1e-8,
                "joint {i} at q = {q:?}: Q {} against −∂V/∂q {}",
                f[i],
                -grad
            );
        }
    }
}

#[test]
fn bad_trees_are_refused_naming_the_body() {
    let mut bodies: Vec<TreeBody> = (0..2)
        .map(|i| {
            body(
                &format!("b{i}"),
                None,
                JointKind::Revolute,
                [0.0, 0.0, 1.0],
                [0.0; 3],
                I3,
                1.0,
                [0.5, 0.0, 0.0],
                None,
            )
        })
        .collect();
    bodies[0].parent = Some(1);
    let e = KinematicTree::new([0.0; 3], bodies.clone()).unwrap_err().to_string();
    assert!(e.contains("body 'b0'") && e.contains("parent"), "{e}");
    bodies[0].parent = None;
    bodies[1].axis = [0.0; 3];
    let e = KinematicTree::new([0.0; 3], bodies.clone()).unwrap_err().to_string();
    assert!(e.contains("body 'b1'") && e.contains("axis"), "{e}");
    bodies[1].axis = [0.0, 0.0, 1.0];
    bodies[1].rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
    let e = KinematicTree::new([0.0; 3], bodies.clone()).unwrap_err().to_string();
    assert!(e.contains("body 'b1'") && e.contains("rotation"), "{e}");
    bodies[1].rotation = I3;
    bodies[1].mass = f64::NAN;
    let e = KinematicTree::new([0.0; 3], bodies).unwrap_err().to_string();
    assert!(e.contains("b1") && e.contains("mass"), "{e}");
}

#[test]
fn a_joint_without_inertia_is_reported_not_divided_by() {
    // A point mass on its own revolute axis: no inertia about the joint (D = 0).
    let mut b = body(
        "spinner",
        None,
        JointKind::Revolute,
        [0.0, 0.0, 1.0],
        [0.0; 3],
        I3,
        1.0,
        [0.0; 3],
        None,
    );
    b.inertia = [[0.0; 3]; 3];
    let tree = KinematicTree::new([0.0, 0.0, -9.81], vec![b]).expect("valid description");
    let sys = JointSpace::new(tree.clone());
    let mut qdd = [0.0];
    let e = Articulated::new(&tree)
        .solve(&sys, (0.5, &[0.0], &[0.0]), &[], &mut qdd)
        .unwrap_err()
        .to_string();
    assert!(e.contains("spinner") && e.contains("t = 0.5"), "{e}");
}
