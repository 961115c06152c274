//! Every constraint's Jacobian, `C_t` and `Q_d` against finite differences, on random
//! configurations (property tests).
//!
//! * `C_q`: central differences with h = 1e-6 (truncation O(h²) ≈ 1e-12, round-off ≈ 1e-16/h ≈ 1e-10
//!   for values of order 1–10): tolerance 1e-7.
//! * `Q_d`: along the trajectory `q(s) = q₀ + v s + ½ a s²`, `t = t₀ + s`, the exact first derivative
//!   is `Ċ(s) = C_q q̇(s) + C_t`; its central difference (h = 1e-5) gives `C̈(0)`, and
//!   `Q_d = C_q a − C̈`. Error O(h²)·C'''' ≈ 1e-9 plus round-off 1e-16/h ≈ 1e-11: tolerance 1e-6
//!   relative to the size of the terms.

use dalembert_constraints::*;
use dalembert_kinematics::{BodyId, BodyRef, Vec2};
use dalembert_system::{ConstraintSet, TimeFunction};
use proptest::prelude::*;

fn b(i: usize) -> BodyRef {
    BodyRef::Body(BodyId(i))
}

fn harmonic() -> TimeFunction {
    TimeFunction::Harmonic {
        offset: 0.7,
        amplitude: 0.3,
        frequency: 0.8,
        phase: 0.2,
    }
}

/// All constraint kinds between `first` and body 1, with geometry from `p`.
fn constraints(first: BodyRef, p: &[f64; 8]) -> Vec<Box<dyn Constraint>> {
    let u = Vec2::new(p[0], p[1]);
    let w = Vec2::new(p[2], p[3]);
    let dir = Vec2::new(p[4], 1.0 + p[5].abs());
    let pair = [first, b(1)];
    let rev = Revolute::new("rev", pair, [u, w]);
    let pri = Prismatic {
        name: "pri".into(),
        bodies: pair,
        points: [u, w],
        axis: dir,
        angle: p[6],
    };
    vec![
        Box::new(rev.clone()),
        Box::new(pri.clone()),
        Box::new(Rigid {
            name: "rigid".into(),
            bodies: pair,
            points: [u, w],
            angle: p[6],
        }),
        Box::new(Distance {
            name: "dist".into(),
            bodies: pair,
            points: [u, w],
            length: 1.3,
        }),
        Box::new(PointOnLine {
            name: "pol".into(),
            bodies: pair,
            points: [u, w],
            direction: dir,
        }),
        Box::new(Gear {
            name: "gear".into(),
            bodies: pair,
            ratio: p[7],
            reference_angles: [0.1, -0.4],
        }),
        Box::new(RackPinion {
            name: "rack".into(),
            bodies: pair,
            points: [u, w],
            axis: dir,
            radius: 0.3 + p[5].abs(),
            reference: [0.2, 0.1],
        }),
        Box::new(JointAngle::on("jang", &rev, harmonic())),
        Box::new(JointDisplacement::on(
            "jdisp",
            &pri,
            TimeFunction::Polynomial(vec![0.1, 0.4, -0.3, 0.2]),
        )),
        Box::new(DistanceDriver {
            name: "ddist".into(),
            bodies: pair,
            points: [u, w],
            function: harmonic(),
        }),
        Box::new(BodyCoordinate {
            name: "bx".into(),
            body: BodyId(1),
            coordinate: Coordinate::X,
            function: harmonic(),
        }),
        Box::new(BodyCoordinate {
            name: "bth".into(),
            body: BodyId(1),
            coordinate: Coordinate::Angle,
            function: TimeFunction::SmoothStep {
                t0: -1.0,
                t1: 2.0,
                from: 0.0,
                to: 1.0,
            },
        }),
    ]
}

fn check(sys: &ConstraintSystem, t: f64, q: &[f64], v: &[f64], a: &[f64]) -> Result<(), TestCaseError> {
    let m = sys.num_equations();
    let n = q.len();
    let mut vals = sys.values();
    sys.evaluate(t, q, v, &mut vals);
    let jac = sys.jacobian_dense(&vals);
    let h = 1e-6;
    let (mut vp, mut vm) = (sys.values(), sys.values());
    for j in 0..n {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[j] += h;
        qm[j] -= h;
        sys.evaluate(t, &qp, &[], &mut vp);
        sys.evaluate(t, &qm, &[], &mut vm);
        for i in 0..m {
            let fd = (vp.c[i] - vm.c[i]) / (2.0 * h);
            prop_assert!(
                (fd - jac[(i, j)]).abs() < 1e-7,
                "{} C_q[{i},{j}]: fd {fd} vs {}",
                sys.equation(i),
                jac[(i, j)]
            );
        }
    }
    // C_t
    sys.evaluate(t + h, q, &[], &mut vp);
    sys.evaluate(t - h, q, &[], &mut vm);
    for i in 0..m {
        let fd = (vp.c[i] - vm.c[i]) / (2.0 * h);
        prop_assert!(
            (fd - vals.c_t[i]).abs() < 1e-7,
            "{} C_t: fd {fd} vs {}",
            sys.equation(i),
            vals.c_t[i]
        );
    }
    // Q_d from the derivative of the exact velocity residual along a trajectory.
    let hs = 1e-5;
    let cdot = |s: f64| -> Vec<f64> {
        let qs: Vec<f64> = (0..n).map(|k| q[k] + v[k] * s + 0.5 * a[k] * s * s).collect();
        let vs: Vec<f64> = (0..n).map(|k| v[k] + a[k] * s).collect();
        let mut vv = sys.values();
        sys.evaluate(t + s, &qs, &vs, &mut vv);
        let mut out = vec![0.0; m];
        sys.velocity_residual(&vv, &vs, &mut out);
        out
    };
    let (cp, cm) = (cdot(hs), cdot(-hs));
    let mut ja = vec![0.0; m];
    sys.jacobian_mul(&vals, a, &mut ja);
    for i in 0..m {
        let cdd = (cp[i] - cm[i]) / (2.0 * hs);
        let qd_fd = ja[i] - cdd;
        let scale = 1.0 + ja[i].abs() + vals.gamma[i].abs();
        prop_assert!(
            (qd_fd - vals.gamma[i]).abs() < 1e-6 * scale,
            "{} Q_d: fd {qd_fd} vs {}",
            sys.equation(i),
            vals.gamma[i]
        );
    }
    Ok(())
}

/// True for a distance element whose points are closer than 0.3: the distance `|p_j − p_i|` has
/// derivatives growing like `1/|d|^k`, so near coincident points the finite differences (not the
/// analytic terms) lose their accuracy; the coincident case is a documented singularity of the
/// element.
fn too_close(c: &dyn Constraint, q: &[f64], p: &[f64; 8]) -> bool {
    if !c.name().ends_with("dist") {
        return false;
    }
    let point = |body, u| dalembert_kinematics::PointState::new(&dalembert_kinematics::BodyState::of(body, q, &[]), u);
    let [a, b] = c.bodies();
    let (pa, pb) = (point(a, Vec2::new(p[0], p[1])), point(b, Vec2::new(p[2], p[3])));
    (pb.position - pa.position).norm() < 0.3
}

/// Each constraint of [`constraints`] (from the ground or body 0 to body 1) alone in a system,
/// except those [`too_close`] at `q`.
fn systems(grounded: bool, q: &[f64], p: &[f64; 8]) -> Vec<ConstraintSystem> {
    let first = if grounded { BodyRef::Ground } else { b(0) };
    constraints(first, p)
        .into_iter()
        .filter(|c| !too_close(c.as_ref(), q, p))
        .map(|c| ConstraintSystem::new(2, vec![c]).unwrap())
        .collect()
}

fn vec_strategy(len: usize, r: f64) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-r..r, len)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn jacobian_ct_and_qd_match_finite_differences(
        q in vec_strategy(6, 2.0),
        v in vec_strategy(6, 3.0),
        a in vec_strategy(6, 3.0),
        p in prop::array::uniform8(-1.5f64..1.5),
        t in 0.0f64..2.0,
        grounded in any::<bool>(),
    ) {
        for sys in systems(grounded, &q, &p) {
            check(&sys, t, &q, &v, &a)?;
        }
    }
}

/// `Σ_k λ_k ∂²C_k/∂q²` from [`Constraint::weighted_hessian`] against central differences of
/// `C_qᵀ λ` (h = 1e-6: truncation O(h²) ≈ 1e-12, round-off ≈ 1e-16 |λ| / h ≈ 1e-9 for multipliers
/// up to 10): tolerance 1e-6. `first` is the ground or body 0, the second body is body 1.
fn check_hessian(sys: &ConstraintSystem, t: f64, q: &[f64], lambda: &[f64]) -> Result<(), TestCaseError> {
    let c = &sys.constraints()[0];
    let [a, b] = c.bodies();
    let (sa, sb) = (
        dalembert_kinematics::BodyState::of(a, q, &[]),
        dalembert_kinematics::BodyState::of(b, q, &[]),
    );
    let lam = &lambda[..c.num_equations()];
    let h = c
        .weighted_hessian(t, &sa, &sb, lam)
        .ok_or_else(|| TestCaseError::fail(format!("{}: no second derivatives", c.name())))?;
    let coordinate = |side: usize, k: usize| [a, b][side].id().map(|id| 3 * id.0 + k);
    let mut dense = [[0.0; 6]; 6];
    for (r, row) in h.iter().enumerate() {
        for (col, v) in row.iter().enumerate() {
            if let (Some(i), Some(j)) = (coordinate(r / 3, r % 3), coordinate(col / 3, col % 3)) {
                dense[i][j] += v;
            }
        }
    }
    let force = |qs: &[f64]| {
        let mut vals = sys.values();
        sys.evaluate(t, qs, &[], &mut vals);
        let mut f = vec![0.0; 6];
        sys.jacobian_transpose_mul_add(&vals, 1.0, lam, &mut f);
        f
    };
    let step = 1e-6;
    for j in 0..6 {
        let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
        qp[j] += step;
        qm[j] -= step;
        let (fp, fm) = (force(&qp), force(&qm));
        for i in 0..6 {
            let fd = (fp[i] - fm[i]) / (2.0 * step);
            prop_assert!(
                (fd - dense[i][j]).abs() < 1e-6,
                "{}: ∂(C_qᵀλ)_{i}/∂q_{j}: fd {fd} vs {}",
                c.name(),
                dense[i][j]
            );
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn weighted_hessians_match_finite_differences(
        q in vec_strategy(6, 2.0),
        lambda in vec_strategy(3, 10.0),
        p in prop::array::uniform8(-1.5f64..1.5),
        t in 0.0f64..2.0,
        grounded in any::<bool>(),
    ) {
        for sys in systems(grounded, &q, &p) {
            check_hessian(&sys, t, &q, &lambda)?;
        }
    }
}

#[test]
fn bad_constraints_are_rejected_by_name() {
    let same = Revolute::new("self-pin", [b(0), b(0)], [Vec2::zeros(), Vec2::zeros()]);
    let err = ConstraintSystem::new(1, vec![Box::new(same)]).unwrap_err();
    assert!(err.to_string().contains("self-pin"), "{err}");
    let missing = Revolute::new("far", [BodyRef::Ground, b(5)], [Vec2::zeros(), Vec2::zeros()]);
    let err = ConstraintSystem::new(2, vec![Box::new(missing)]).unwrap_err();
    assert!(err.to_string().contains("far"), "{err}");
    let zero_axis = Prismatic {
        name: "bad-axis".into(),
        bodies: [BodyRef::Ground, b(0)],
        points: [Vec2::zeros(); 2],
        axis: Vec2::zeros(),
        angle: 0.0,
    };
    let err = ConstraintSystem::new(1, vec![Box::new(zero_axis)]).unwrap_err();
    assert!(err.to_string().contains("bad-axis"), "{err}");
}
