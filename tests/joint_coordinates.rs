//! Spatial trees in joint coordinates (`Model::joint_coordinates`, `dalembert_system::JointSpace`)
//! against the same models in absolute coordinates, where the three formulations solve the
//! constrained equations with Lagrange multipliers: a different set of equations for the same
//! motion.
//!
//! Asserted:
//! * at random joint states, the state mapped to absolute coordinates satisfies the model's
//!   constraints (1e-12 positions, 1e-11 velocities): the conversion keeps the model's kinematics;
//! * every formulation in absolute coordinates gives the accelerations of the articulated-body
//!   algorithm (mapped: centre-of-mass and body-frame angular accelerations) to 1e-9 of the
//!   largest, the formulations' agreement tolerance (`tests/agreement.rs`);
//! * every formulation and back end in joint coordinates gives the same `q̈` (the articulated-body
//!   algorithm, and the dense LU of the composite-rigid-body `M`) to 1e-10 relative;
//! * every integrator runs the joint coordinates and converges at its order (errors at two steps
//!   against a Dormand–Prince run of the absolute model at tolerance 1e-12);
//! * energy is conserved to RK4's accuracy, its drift falling by 2⁴ with the step;
//! * what joint coordinates cannot take is refused naming the element.

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::{Augmented, AugmentedOptions, Backend};
use dalembert::embedding::Embedding;
use dalembert::integrators::{integrate, IntegratorOptions, Method, Stabilization, StepControl, METHODS};
use dalembert::spatial::euler_parameters::from_rotation_vector;
use dalembert::spatial::{Body, BodyRef, Joint, JointCoordinates, JointKind, Model, ModelBuilder};
use dalembert::system::tree::Articulated;
use dalembert::system::{Formulation, MultibodySystem};
use dalembert_testkit::fuzz::Rng;
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// Uniform in `[lo, hi)`.
fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

/// A branched spatial tree: a base on a tilted revolute axis, an arm on it, a slider on the arm
/// (prismatic), a second arm from the base; rotated body frames and full inertia tensors.
fn branched() -> Arc<Model> {
    // Principal moments ≈ 0.049, 0.071, 0.080: a rigid body's (the triangle inequality holds).
    let inertia = |s: f64| Matrix3::new(0.08, 0.005, -0.004, 0.005, 0.07, 0.002, -0.004, 0.002, 0.05) * s;
    let turned = |x: f64, y: f64, z: f64| from_rotation_vector(&Vector3::new(x, y, z));
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let base = b.body(
        Body::new("base", 2.0, [0.0; 3])
            .with_inertia(inertia(2.0))
            .at([0.1, 0.0, 0.4])
            .oriented(turned(0.3, -0.2, 0.5)),
    );
    let arm = b.body(
        Body::new("arm", 1.2, [0.0; 3])
            .with_inertia(inertia(1.2))
            .at([0.6, 0.2, 0.7])
            .oriented(turned(-0.4, 0.1, 0.2)),
    );
    let slider = b.body(
        Body::new("slider", 0.6, [0.0; 3])
            .with_inertia(inertia(0.6))
            .at([1.2, 0.3, 0.6]),
    );
    let other = b.body(
        Body::new("other", 0.9, [0.0; 3])
            .with_inertia(inertia(0.9))
            .at([-0.3, 0.5, 0.5])
            .oriented(turned(0.0, 0.9, -0.3)),
    );
    b.joint(Joint::revolute(
        "j_base",
        BodyRef::Ground,
        base,
        [0.0, 0.0, 0.3],
        [0.2, 0.1, 1.0],
    ));
    b.joint(Joint::revolute("j_arm", base, arm, [0.4, 0.1, 0.6], [0.0, 1.0, 0.2]));
    b.joint(Joint::new(
        "j_slider",
        JointKind::Prismatic,
        arm,
        slider,
        [1.0, 0.25, 0.6],
        [1.0, 0.1, -0.1],
    ));
    b.joint(Joint::revolute(
        "j_other",
        base,
        other,
        [-0.1, 0.3, 0.45],
        [1.0, 0.0, 0.3],
    ));
    Arc::new(b.build().expect("the branched tree is well formed"))
}

/// The tree's state at joint state `(q, q̇)` mapped to the model's absolute coordinates, with the
/// accelerations `v̇` of the articulated-body algorithm mapped the same way.
fn mapped(jc: &JointCoordinates, bodies: usize, q: &[f64], qd: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let sys = jc.system();
    let tree = sys.tree();
    let mut aba = Articulated::new(tree);
    let mut qdd = vec![0.0; tree.len()];
    aba.accelerations(tree, 0.0, q, qd, &mut qdd).expect("evaluation");
    let mut frames = jc.frames();
    let (mut qa, mut va, mut vdot) = (vec![0.0; 7 * bodies], vec![0.0; 6 * bodies], vec![0.0; 6 * bodies]);
    jc.absolute(q, qd, &mut frames, &mut qa, &mut va);
    let (acc, vel) = aba.body_motion();
    let g = Vector3::from(tree.gravity());
    for (t, &k) in jc.model_bodies().iter().enumerate() {
        let c = Vector3::from(tree.bodies()[t].com);
        // The recursion's accelerations include the base's −g: add g back (body components).
        let ao = acc[t].v + frames[t].rotation.tr_mul(&g);
        let ((al, om), vo) = ((acc[t].w, vel[t].w), vel[t].v);
        // Classical acceleration of the centre of mass from the spatial one (body components).
        let ac = frames[t].rotation * (ao + al.cross(&c) + om.cross(&(vo + om.cross(&c))));
        vdot[6 * k..6 * k + 3].copy_from_slice(ac.as_slice());
        vdot[6 * k + 3..6 * k + 6].copy_from_slice(al.as_slice());
    }
    (qa, va, vdot)
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

#[test]
fn absolute_formulations_give_the_articulated_body_accelerations() {
    let cases: Vec<(&str, Arc<Model>)> = vec![
        ("chain3d-3", dalembert_testkit::spatial::chain3d(3)),
        ("chain3d-8", dalembert_testkit::spatial::chain3d(8)),
        ("branched", branched()),
    ];
    let mut worst = 0.0f64;
    for (name, model) in cases {
        let jc = model
            .joint_coordinates()
            .expect("a tree of revolute and prismatic joints");
        let n = jc.system().tree().len();
        let bodies = model.bodies().len();
        let sys = model.constraints();
        let m = sys.num_equations();
        for seed in 0..4u64 {
            let mut rng = Rng::new(100 + seed);
            let q: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -1.5, 1.5)).collect();
            let qd: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -3.0, 3.0)).collect();
            let (qa, va, vdot) = mapped(&jc, bodies, &q, &qd);
            let (mut c, mut cdot) = (vec![0.0; m], vec![0.0; m]);
            sys.residuals(0.0, &qa, &va, &mut sys.values(), &mut c, &mut cdot);
            assert!(
                max_abs(&c) < 1e-12 && max_abs(&cdot) < 1e-11,
                "{name}, seed {seed}: |C| {:e}, |Ċ| {:e}",
                max_abs(&c),
                max_abs(&cdot)
            );
            let model_dyn: Arc<dyn MultibodySystem> = model.clone();
            let formulations: Vec<Box<dyn Formulation>> = vec![
                Box::new(Augmented::with_defaults(model_dyn.clone()).expect("augmented")),
                Box::new(Embedding::with_defaults(model_dyn.clone())),
                Box::new(Amalgamated::with_defaults(model_dyn)),
            ];
            let scale = max_abs(&vdot);
            for mut f in formulations {
                let (mut qdd, mut lam) = (vec![0.0; va.len()], vec![0.0; m]);
                f.accelerations(0.0, &qa, &va, None, &mut qdd, &mut lam)
                    .expect("evaluation");
                let diff = max_diff(&qdd, &vdot);
                worst = worst.max(diff / scale);
                assert!(
                    diff <= 1e-9 * scale,
                    "{name}, seed {seed}, {}: |Δv̇| {diff:e} of {scale:e}",
                    f.name()
                );
            }
        }
    }
    println!("largest difference from the articulated-body algorithm, relative: {worst:e}");
}

#[test]
fn every_formulation_and_back_end_agrees_in_joint_coordinates() {
    for model in [dalembert_testkit::spatial::chain3d(6), branched()] {
        let sys: Arc<dyn MultibodySystem> = model.joint_coordinates().expect("a tree").system();
        let n = sys.layout().n_v();
        assert_eq!(sys.num_equations(), 0);
        let dense = AugmentedOptions {
            backend: Backend::Dense,
            ..Default::default()
        };
        let mut formulations: Vec<(&str, Box<dyn Formulation>)> = vec![
            (
                "augmented, dense LU of M",
                Box::new(Augmented::new(sys.clone(), dense).expect("dense")),
            ),
            (
                "augmented",
                Box::new(Augmented::with_defaults(sys.clone()).expect("augmented")),
            ),
            ("embedding", Box::new(Embedding::with_defaults(sys.clone()))),
            ("amalgamated", Box::new(Amalgamated::with_defaults(sys.clone()))),
        ];
        let mut rng = Rng::new(7);
        for _ in 0..3 {
            let q: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -2.0, 2.0)).collect();
            let qd: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -2.0, 2.0)).collect();
            let mut results = Vec::new();
            for (name, f) in &mut formulations {
                let mut qdd = vec![0.0; n];
                f.accelerations(0.0, &q, &qd, None, &mut qdd, &mut [])
                    .expect("evaluation");
                results.push((*name, qdd));
            }
            let (_, reference) = &results[0];
            for (name, qdd) in &results[1..] {
                let diff = max_diff(qdd, reference);
                assert!(diff <= 1e-10 * max_abs(reference), "{name}: |Δq̈| {diff:e}");
            }
        }
    }
}

/// Final absolute positions after `end` seconds: `model` in joint coordinates with `opts`.
fn run_joint_space(model: &Model, opts: &IntegratorOptions, end: f64) -> Vec<f64> {
    let jc = model.joint_coordinates().expect("a tree");
    let (q0, qd0) = jc.initial_state();
    let mut f = Augmented::with_defaults(jc.system()).expect("formulation");
    let mut last = (q0.clone(), qd0.clone());
    integrate(&mut f, 0.0, end, &q0, &qd0, opts, &mut |s| {
        last = (s.q.to_vec(), s.qd.to_vec())
    })
    .expect("run");
    let (mut qa, mut va) = model.initial_state();
    jc.absolute(&last.0, &last.1, &mut jc.frames(), &mut qa, &mut va);
    qa
}

/// Position error (centres of mass; Euler parameters as given) against `reference`.
fn position_error(q: &[f64], reference: &[f64]) -> f64 {
    // Euler parameters p and −p are one rotation: compare with the sign that is closer.
    q.chunks(7)
        .zip(reference.chunks(7))
        .map(|(a, b)| {
            let s = if a[3..].iter().zip(&b[3..]).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
                -1.0
            } else {
                1.0
            };
            let r = max_diff(&a[..3], &b[..3]);
            let p = a[3..]
                .iter()
                .zip(&b[3..])
                .fold(0.0f64, |m, (x, y)| m.max((s * x - y).abs()));
            r.max(p)
        })
        .fold(0.0, f64::max)
}

#[test]
fn every_integrator_converges_at_its_order_in_joint_coordinates() {
    let model = dalembert_testkit::spatial::chain3d(4);
    let end = 1.0;
    // Reference: the absolute coordinates, Dormand–Prince at 1e-12 with projection.
    let reference = {
        let sys: Arc<dyn MultibodySystem> = model.clone();
        let mut f = Augmented::with_defaults(sys).expect("formulation");
        let method = Method::dopri5(1e-12, 1e-14);
        let opts = IntegratorOptions::fixed(method, 1e-3, end)
            .with_stabilization(Stabilization::Projection { tolerance: 1e-12 });
        let (q0, qd0) = model.initial_state();
        let mut last = q0.clone();
        integrate(&mut f, 0.0, end, &q0, &qd0, &opts, &mut |s| last = s.q.to_vec()).expect("reference run");
        last
    };
    for entry in METHODS {
        if entry.control == StepControl::Adaptive {
            let method = Method::of(entry)
                .with("rtol", 1e-9)
                .unwrap()
                .with("atol", 1e-11)
                .unwrap();
            let err = position_error(
                &run_joint_space(&model, &IntegratorOptions::fixed(method, 1e-3, 0.1), end),
                &reference,
            );
            assert!(err < 1e-7, "{}: error {err:e} at rtol 1e-9", entry.name);
            continue;
        }
        let errs: Vec<f64> = [8e-3, 4e-3]
            .iter()
            .map(|&h| {
                position_error(
                    &run_joint_space(&model, &IntegratorOptions::fixed(Method::of(entry), h, 0.1), end),
                    &reference,
                )
            })
            .collect();
        let observed = (errs[0] / errs[1]).log2();
        // Within 0.7 of the order: the errors are in the asymptotic range at these steps.
        assert!(
            observed > entry.order as f64 - 0.7,
            "{}: errors {:e} and {:e} at 8 and 4 ms, observed order {observed:.2}, expected {}",
            entry.name,
            errs[0],
            errs[1],
            entry.order
        );
    }
}

#[test]
fn energy_is_conserved_to_the_order_of_rk4() {
    let model = dalembert_testkit::spatial::chain3d(8);
    let jc = model.joint_coordinates().expect("a tree");
    let (q0, qd0) = jc.initial_state();
    let drift = |h: f64| {
        let mut f = Augmented::with_defaults(jc.system()).expect("formulation");
        let e0 = f.energy(0.0, &q0, &qd0).total();
        let mut worst = 0.0f64;
        let opts = IntegratorOptions::fixed(Method::rk4(), h, 0.01);
        integrate(&mut f, 0.0, 3.0, &q0, &qd0, &opts, &mut |s| {
            worst = worst.max((s.energy - e0).abs())
        })
        .expect("run");
        worst
    };
    // Measured (2026-11-25): 2.0e-6, 2.6e-7, 1.7e-8, 1.1e-9 J at 4, 2, 1, 0.5 ms: ratios 7.5, 15.7,
    // 15.7, so the asymptotic range starts at 2 ms; compare there.
    let (coarse, fine) = (drift(2e-3), drift(1e-3));
    // The chain falls through 8 m: kinetic energies of order 100 J.
    assert!(fine < 1e-6, "energy drift {fine:e} J at 1 ms");
    assert!(
        coarse / fine > 2f64.powi(4) * 0.6,
        "drift {coarse:e} J at 2 ms, {fine:e} J at 1 ms: not fourth order"
    );
}

#[test]
fn what_joint_coordinates_cannot_take_is_refused_naming_it() {
    let e = dalembert_testkit::spatial::heavy_top()
        .joint_coordinates()
        .unwrap_err()
        .to_string();
    assert!(e.contains("joint 'pivot'") && e.contains("spherical"), "{e}");
    let e = dalembert_testkit::spatial::forced_double_pendulum()
        .joint_coordinates()
        .unwrap_err()
        .to_string();
    assert!(e.contains("force '"), "{e}");
    // A closed loop: two links on the ground, pinned to each other.
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let l = b.body(Body::new("left", 1.0, [0.01, 0.1, 0.1]).at([0.0, 0.0, -0.5]));
    let r = b.body(Body::new("right", 1.0, [0.01, 0.1, 0.1]).at([1.0, 0.0, -0.5]));
    b.joint(Joint::revolute(
        "a",
        BodyRef::Ground,
        l,
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
    ));
    b.joint(Joint::revolute(
        "b",
        BodyRef::Ground,
        r,
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
    ));
    b.joint(Joint::revolute("c", l, r, [0.5, 0.0, -1.0], [0.0, 1.0, 0.0]));
    let e = b.build().unwrap().joint_coordinates().unwrap_err().to_string();
    assert!(e.contains("tree"), "{e}");
    // Bodies joined to each other but not to the ground (as many joints as bodies).
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let [a, c, d] = ["a", "c", "d"].map(|n| b.body(Body::new(n, 1.0, [0.01, 0.1, 0.1])));
    b.joint(Joint::revolute("ja", BodyRef::Ground, a, [0.0; 3], [0.0, 1.0, 0.0]));
    b.joint(Joint::revolute("jc", c, d, [0.0; 3], [0.0, 1.0, 0.0]));
    b.joint(Joint::revolute("jd", d, c, [0.0; 3], [0.0, 0.0, 1.0]));
    let e = b.build().unwrap().joint_coordinates().unwrap_err().to_string();
    assert!(e.contains("body 'c'") && e.contains("ground"), "{e}");
}

/// A sample of a run: time, positions, velocities, multipliers.
type Row = (f64, Vec<f64>, Vec<f64>, Vec<f64>);

/// The samples of a scene's run.
fn samples(scene: &dalembert::Scene) -> Vec<Row> {
    let mut out = Vec::new();
    scene
        .simulation()
        .run(&mut |s| out.push((s.t, s.q.to_vec(), s.qd.to_vec(), s.lambda.to_vec())))
        .expect("run");
    out
}

#[test]
fn a_scene_in_joint_coordinates_gives_the_same_outputs() {
    // chain3d-6 as a scene, 1 s of RK4 at 1 ms, both ways. The two runs integrate different
    // equations for the same motion: their states differ by the two RK4 truncation errors (at
    // most 1.3e-10 m at t = 1 s for chain3d-32 against the anchors' reference, so 1e-8 leaves
    // room); the multipliers are the model's augmented formulation's at nearly the same state,
    // within 1e-6 of their largest (the reactions scale with the accelerations, of order 10).
    let text = dalembert_testkit::spatial::chain3d_toml(6, 1.0);
    let absolute = dalembert::Scene::from_toml(&text, "chain3d-6").expect("scene");
    let joint = dalembert::Scene::from_toml(
        &text.replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n"),
        "chain3d-6 joint",
    )
    .expect("scene in joint coordinates");
    assert_eq!(joint.settings.coordinates, dalembert::Coordinates::Joint);
    let (a, j) = (samples(&absolute), samples(&joint));
    assert_eq!(a.len(), j.len());
    let lambda_scale = a.iter().map(|s| max_abs(&s.3)).fold(0.0, f64::max);
    for (sa, sj) in a.iter().zip(&j) {
        assert_eq!(sa.0, sj.0);
        let dq = position_error(&sj.1, &sa.1);
        let dv = max_diff(&sj.2, &sa.2);
        let dl = max_diff(&sj.3, &sa.3);
        assert!(dq < 1e-8 && dv < 1e-7, "t = {}: |Δq| {dq:e}, |Δv| {dv:e}", sa.0);
        assert!(
            dl < 1e-6 * lambda_scale,
            "t = {}: |Δλ| {dl:e} of {lambda_scale:e}",
            sa.0
        );
    }
}

#[test]
fn scenes_that_joint_coordinates_cannot_take_are_refused_at_the_key() {
    let top = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/heavy-top.toml")).unwrap();
    let top = top.replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n");
    let e = dalembert::Scene::from_toml(&top, "heavy-top.toml")
        .unwrap_err()
        .to_string();
    let line = top.lines().position(|l| l.starts_with("coordinates")).unwrap() + 1;
    assert!(
        e.contains(&format!("heavy-top.toml:{line}:")) && e.contains("joint 'pivot'"),
        "{e}"
    );
    // A simulation set to joint coordinates after loading takes that path, and refuses too.
    let mut sim = dalembert::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/heavy-top.toml"))
        .unwrap()
        .simulation();
    sim.coordinates = dalembert::Coordinates::Joint;
    match sim.run(&mut |_| {}) {
        Err(dalembert::SimulationError::JointCoordinates(e)) => assert!(e.to_string().contains("joint 'pivot'"), "{e}"),
        other => panic!("expected the joint-coordinates refusal, got {other:?}"),
    }
    let planar = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/pendulum.toml")).unwrap();
    let planar = if planar.contains("[simulation]\n") {
        planar.replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n")
    } else {
        planar + "\n[simulation]\ncoordinates = \"joint\"\n"
    };
    let e = dalembert::Scene::from_toml(&planar, "pendulum.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("spatial"), "{e}");
    let typo = dalembert_testkit::spatial::chain3d_toml(2, 1.0)
        .replace("[simulation]\n", "[simulation]\ncoordinates = \"joints\"\n");
    let e = dalembert::Scene::from_toml(&typo, "typo.toml").unwrap_err().to_string();
    assert!(e.contains("joints") && e.contains("absolute"), "{e}");
}

#[test]
fn trade_measures_joint_coordinates_beside_the_formulations() {
    use dalembert::trade::{trade, TradeGrid};
    let scene = dalembert::Scene::from_toml(&dalembert_testkit::spatial::chain3d_toml(4, 0.5), "chain3d-4").unwrap();
    let grid = TradeGrid {
        integrators: vec!["rk4".into()],
        stabilizations: vec!["projection".into()],
        steps: vec![4e-3, 2e-3],
        ..TradeGrid::default()
    };
    let t = trade(&scene, &grid, &mut |_, _| {}).expect("trade");
    for h in [4e-3, 2e-3] {
        let row = |name: &str| {
            t.runs
                .iter()
                .find(|r| r.method == name && r.parameter == h)
                .unwrap_or_else(|| {
                    panic!(
                        "{name} at {h}: {:?}",
                        t.runs.iter().map(|r| &r.method).collect::<Vec<_>>()
                    )
                })
        };
        let (joint, augmented) = (row("joint/rk4"), row("augmented/rk4/projection"));
        assert_eq!(joint.status, "ok");
        // The joints hold by construction in joint coordinates (round-off of the mapping).
        assert!(joint.constraint < 1e-12, "max |C| {:e}", joint.constraint);
        // One method on one motion: RK4's truncation errors of the two sets of equations are of
        // one size (measured on chain3d-16: 0.85 of the augmented formulation's).
        let (ej, ea) = (joint.error.unwrap(), augmented.error.unwrap());
        assert!(
            ej < 3.0 * ea && ea < 3.0 * ej,
            "h = {h}: joint {ej:e}, augmented {ea:e}"
        );
    }
    // A model that cannot take joint coordinates: the default grid leaves them out, a grid that
    // names them is refused.
    let loop_scene = dalembert::Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/rssr.toml")).unwrap();
    let small = TradeGrid {
        integrators: vec!["rk4".into()],
        stabilizations: vec!["projection".into()],
        steps: vec![1e-2],
        end: Some(0.05),
        ..TradeGrid::default()
    };
    let t = trade(&loop_scene, &small, &mut |_, _| {}).expect("trade");
    assert!(t.runs.iter().all(|r| !r.method.starts_with("joint")));
    let only_joint = TradeGrid {
        formulations: vec!["joint".into()],
        ..small
    };
    let e = trade(&loop_scene, &only_joint, &mut |_, _| {}).unwrap_err();
    assert!(e.contains("formulation 'joint'"), "{e}");
}

#[test]
fn a_stop_request_ends_a_joint_coordinate_run_at_a_sample() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let text = dalembert_testkit::spatial::chain3d_toml(4, 1.0)
        .replace("[simulation]\n", "[simulation]\ncoordinates = \"joint\"\n");
    let sim = dalembert::Scene::from_toml(&text, "chain3d-4").unwrap().simulation();
    let cancel = AtomicBool::new(false);
    let mut times = Vec::new();
    let r = sim.run_cancellable(
        &mut |s| {
            times.push(s.t);
            // Asked to stop during the third output interval.
            if times.len() == 3 {
                cancel.store(true, Ordering::Relaxed);
            }
        },
        &cancel,
    );
    match r {
        Err(dalembert::SimulationError::Integration(f)) => {
            assert!(
                matches!(f.error, dalembert::integrators::IntegrationError::Interrupted { .. }),
                "{f}"
            );
        }
        other => panic!("expected an interrupted run, got {other:?}"),
    }
    // The samples up to the request, none after: t = 0, 0.01, 0.02.
    assert_eq!(times.len(), 3, "{times:?}");
}

/// chain3d-6 with its [simulation] table set to joint or absolute coordinates.
fn chain_scene(joint: bool) -> dalembert::Scene {
    let text = dalembert_testkit::spatial::chain3d_toml(6, 1.0);
    let coordinates = if joint { "joint" } else { "absolute" };
    let text = text.replace(
        "[simulation]\n",
        &format!("[simulation]\ncoordinates = \"{coordinates}\"\n"),
    );
    dalembert::Scene::from_toml(&text, "chain3d-6").expect("scene")
}

#[test]
fn a_simulator_in_joint_coordinates_is_the_run_in_them() {
    // Advanced in uneven chunks (stopping between steps and going on), the simulator in joint
    // coordinates passes through every output time of the run from start to end with the same
    // sample, bitwise: the same steps of the same method on the same tree, mapped by the same
    // map and evaluated by the same formulation.
    let scene = chain_scene(true);
    let run = samples(&scene);
    let mut sim = scene.simulator().expect("simulator in joint coordinates");
    let (q_col, qd_col): (Vec<usize>, Vec<usize>) = {
        let cols = sim.columns().to_vec();
        let bodies = scene.model.body_names();
        let at = |b: &str, c: &str| cols.iter().position(|x| *x == format!("{b}.{c}")).unwrap();
        (
            bodies
                .iter()
                .flat_map(|b| ["x", "y", "z", "e0", "e1", "e2", "e3"].map(|c| at(b, c)))
                .collect(),
            bodies
                .iter()
                .flat_map(|b| ["vx", "vy", "vz"].map(|c| at(b, c)))
                .collect(),
        )
    };
    let mut chunk = 0.0013;
    for (k, (t, q, qd, _)) in run.iter().enumerate().skip(1) {
        // An uneven stop inside the interval first (every third one), then the output time.
        if k % 3 == 0 {
            sim.advance_to(t - chunk).unwrap();
            chunk = (chunk * 1.7) % 0.004;
        }
        sim.advance_to(*t).unwrap();
        assert_eq!(sim.time(), *t);
        let (sq, sqd) = sim.state();
        assert_eq!(sq, &q[..], "positions at t = {t}");
        assert_eq!(sqd, &qd[..], "velocities at t = {t}");
        let row = sim.row().unwrap().to_vec();
        for (i, &c) in q_col.iter().enumerate() {
            assert_eq!(row[c], q[i], "column {} at t = {t}", sim.columns()[c]);
        }
        for (i, &c) in qd_col.iter().enumerate() {
            // The body's centre-of-mass velocity: the first three of its six velocities.
            assert_eq!(
                row[c],
                qd[6 * (i / 3) + i % 3],
                "column {} at t = {t}",
                sim.columns()[c]
            );
        }
    }
}

#[test]
fn a_state_set_in_joint_coordinates_moves_the_tree() {
    // The same perturbed state set in a simulator in joint coordinates and in one in absolute
    // coordinates at t = 0.3: both assemble it with the same kinematic solve (the same `Moved`,
    // to round-off), then integrate different equations for the same motion, so at t = 0.8 they
    // differ by the two RK4 truncation errors (1e-8, as in
    // `a_scene_in_joint_coordinates_gives_the_same_outputs`). The joint simulator's statistics go
    // on across the rebuilt tree (the steps before and after are counted).
    let mut joint = chain_scene(true).simulator().unwrap();
    let mut absolute = chain_scene(false).simulator().unwrap();
    for sim in [&mut joint, &mut absolute] {
        sim.advance_to(0.3).unwrap();
    }
    let steps_before = joint.statistics().steps;
    let (mut q, mut qd) = (joint.state().0.to_vec(), joint.state().1.to_vec());
    q[0] += 1e-3; // the first link's centre of mass off its joint
    q[7 * 2 + 3] += 2e-3; // the third link's Euler parameters off their unit norm and joint
    qd[6 * 3 + 4] += 0.5; // the fourth link turning about a direction its joint forbids
    let moved_j = joint.set_state(&q, &qd).unwrap();
    let moved_a = absolute.set_state(&q, &qd).unwrap();
    assert!(
        (moved_j.positions - moved_a.positions).abs() < 1e-12,
        "{moved_j:?} {moved_a:?}"
    );
    assert!(
        (moved_j.velocities - moved_a.velocities).abs() < 1e-12,
        "{moved_j:?} {moved_a:?}"
    );
    assert!(moved_j.positions > 1e-4 && moved_j.velocities > 1e-2, "{moved_j:?}");
    // The joint simulator's state is the assembled one mapped to the rebuilt tree and back: equal
    // to round-off of the map along the chain (6 links, positions up to 5.4 m: 1e-13).
    let dq0 = position_error(joint.state().0, absolute.state().0);
    assert!(dq0 < 1e-13, "the same assembled positions: |Δq| {dq0:e}");
    for sim in [&mut joint, &mut absolute] {
        sim.advance_to(0.8).unwrap();
    }
    let dq = position_error(joint.state().0, absolute.state().0);
    let dv = max_diff(joint.state().1, absolute.state().1);
    assert!(dq < 1e-8 && dv < 1e-7, "|Δq| {dq:e}, |Δv| {dv:e}");
    let stats = joint.statistics();
    assert_eq!(stats.steps, steps_before + 500, "300 steps of 1 ms, then 500");
}

#[test]
fn the_loads_a_tree_computes_are_the_norms_of_the_joints_multipliers() {
    // Joint friction's load in joint coordinates is the force each joint transmits, from the
    // tree's recursive Newton–Euler pass (`JointSpace::reaction_loads`, (F6) of
    // `docs/friction.md`); in absolute coordinates the norm of the joint's own multipliers (a
    // pin's three force rows, a guide's two lateral rows). On the branched tree (tilted axes,
    // rotated frames, full inertia tensors, a prismatic joint), at random joint states with
    // velocities and with a torque or force along one joint (a friction's, which must not load
    // it), each joint's load by both, within 1e-10 of the largest load (round-off of forces of
    // about 30 N).
    let specs = |model: &Model| {
        model
            .joint_names()
            .map(|j| dalembert::spatial::friction::SpatialFriction {
                joint: j.into(),
                coefficient: 1.0,
                radius: 1.0,
                viscous: 0.0,
                constant: 0.0,
                stick_speed: 1e-6,
            })
            .collect::<Vec<_>>()
    };
    let plain = branched();
    let model = Arc::new((*plain).clone().with_frictions(specs(&plain)).expect("frictions"));
    let jc = model.joint_coordinates().expect("a tree");
    let space = jc.system();
    let (n, bodies) = (space.tree().len(), model.bodies().len());
    let m = model.num_equations();
    let loads_len = space.num_reaction_loads();
    assert_eq!(loads_len, 3 * n);
    let mut worst = 0.0f64;
    for seed in 0..6u64 {
        let mut rng = Rng::new(300 + seed);
        let q: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -1.5, 1.5)).collect();
        let qd: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -3.0, 3.0)).collect();
        let (qa, va, _) = mapped(&jc, bodies, &q, &qd);
        // A force of 7 along friction element `pushed` (none for the first seeds).
        let pushed = (seed >= 2).then_some(seed as usize % n);
        let mut row = dalembert::system::SlipRow::default();
        let (mut extra_joint, mut extra_model) = (vec![0.0; n], vec![0.0; va.len()]);
        if let Some(k) = pushed {
            space.slip_row(k, 0.0, &q, &qd, &mut row);
            row.entries().iter().for_each(|&(i, g)| extra_joint[i] += 7.0 * g);
            model.slip_row(k, 0.0, &qa, &va, &mut row);
            row.entries().iter().for_each(|&(i, g)| extra_model[i] += 7.0 * g);
        }
        // Joint coordinates: the articulated-body accelerations with the force, then the loads.
        let space_dyn: Arc<dyn MultibodySystem> = space.clone();
        let mut tree = Augmented::with_defaults(space_dyn).expect("augmented on the tree");
        tree.set_extra_force(Some(&extra_joint));
        let mut qdd = vec![0.0; n];
        tree.accelerations(0.0, &q, &qd, None, &mut qdd, &mut [])
            .expect("evaluation");
        let mut loads = vec![0.0; loads_len];
        space.reaction_loads(0.0, &q, &qd, &qdd, false, &mut loads);
        // Absolute coordinates: the multipliers with the same force.
        let model_dyn: Arc<dyn MultibodySystem> = model.clone();
        let mut absolute = Augmented::with_defaults(model_dyn).expect("augmented");
        absolute.set_extra_force(Some(&extra_model));
        let (mut vdot, mut lambda) = (vec![0.0; va.len()], vec![0.0; m]);
        absolute
            .accelerations(0.0, &qa, &va, None, &mut vdot, &mut lambda)
            .expect("evaluation");
        let norm = |rows: &[usize], x: &[f64]| rows.iter().map(|&r| x[r] * x[r]).sum::<f64>().sqrt();
        let pairs: Vec<(f64, f64)> = (model.friction_specs().iter())
            .zip(space.frictions())
            .map(|(a, b)| (norm(&a.load_rows, &lambda), norm(&b.load_rows, &loads)))
            .collect();
        let scale = pairs.iter().fold(0.0f64, |s, p| s.max(p.0));
        assert!(scale > 1.0, "seed {seed}: loads of {scale} N");
        for (k, (a, b)) in pairs.iter().enumerate() {
            worst = worst.max((a - b).abs() / scale);
            assert!(
                (a - b).abs() < 1e-10 * scale,
                "seed {seed}, joint {k} (pushed {pushed:?}): multipliers {a}, tree {b}"
            );
        }
    }
    println!("largest load difference, relative: {worst:e}");
}
