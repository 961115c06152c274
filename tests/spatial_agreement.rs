//! The project's strongest test, for spatial models: the three formulations give the same
//! accelerations and multipliers on generated mechanisms (chains and trees with every
//! degree-of-freedom-keeping joint kind, some closed into loops by distance links), at consistent
//! states with random velocities. The augmented formulation runs with its default back end, the
//! tree factorization and the dense LU.
//!
//! Tolerance: 1e-9 relative to the largest acceleration and multiplier. The three solve the same
//! linear equations by different eliminations (saddle point; velocity transformation; one symmetric
//! system), so they differ by round-off amplified by the conditioning of these small systems
//! (bodies of 0.5–2 kg, moments 0.1–0.2: condition numbers ~1e3–1e5, differences ~1e-12).

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::{Augmented, AugmentedOptions, Backend};
use dalembert::embedding::Embedding;
use dalembert::spatial::euler_parameters::from_axis_angle;
use dalembert::spatial::{Body, BodyRef, Joint, JointKind, Model, ModelBuilder};
use dalembert::system::{ConstraintSet, Formulation, KinematicOptions, MultibodySystem};
use nalgebra::Vector3;
use std::sync::Arc;

/// A small deterministic generator (64-bit LCG, Knuth's constants): reproducible mechanisms.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn vector(&mut self, scale: f64) -> [f64; 3] {
        [
            self.range(-scale, scale),
            self.range(-scale, scale),
            self.range(-scale, scale),
        ]
    }
    fn pick(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// Bodies hung one after the other (or on a random earlier body: a tree), each joined to its
/// parent by a random kind; with `loops`, distance links from some bodies to the ground close
/// loops.
fn mechanism(seed: u64, loops: bool) -> Model {
    let mut rng = Lcg(seed);
    let kinds = [
        JointKind::Spherical,
        JointKind::Revolute,
        JointKind::Universal,
        JointKind::Cylindrical,
        JointKind::Prismatic,
    ];
    let mut b = ModelBuilder::new([0.0, -9.81, 0.0]);
    let n = 2 + rng.pick(5);
    let mut centres: Vec<Vector3<f64>> = Vec::new();
    let mut refs = Vec::new();
    for k in 0..n {
        let parent = if k == 0 { None } else { Some(rng.pick(k)) };
        let anchor = parent.map_or(Vector3::zeros(), |p| centres[p]);
        let joint_point = anchor + Vector3::from(rng.vector(0.5));
        let centre = joint_point + Vector3::from(rng.vector(0.5));
        // Within [0.1, 0.2]: any three satisfy the triangle inequality of a rigid body.
        let principal = [rng.range(0.1, 0.2), rng.range(0.1, 0.2), rng.range(0.1, 0.2)];
        let body = b.body(
            Body::new(&format!("b{k}"), rng.range(0.5, 2.0), principal)
                .at(centre.into())
                .oriented(from_axis_angle(&Vector3::from(rng.vector(1.0)), rng.range(-3.0, 3.0))),
        );
        let parent_ref = parent.map_or(BodyRef::Ground, |p| refs[p]);
        let kind = kinds[rng.pick(kinds.len())];
        let axis = rng.vector(1.0);
        let joint = if kind == JointKind::Universal {
            let a = Vector3::from(axis).normalize();
            let other = Vector3::from(rng.vector(1.0));
            let perpendicular = (other - a * a.dot(&other)).normalize();
            Joint::crossed(
                &format!("j{k}"),
                kind,
                parent_ref,
                body,
                joint_point.into(),
                axis,
                perpendicular.into(),
            )
        } else {
            Joint::new(&format!("j{k}"), kind, parent_ref, body, joint_point.into(), axis)
        };
        b.joint(joint);
        centres.push(centre);
        refs.push(body);
    }
    if loops {
        for k in (1..n).step_by(2) {
            let on_body = centres[k] + Vector3::from(rng.vector(0.3));
            let on_ground = on_body + Vector3::from(rng.vector(1.0));
            b.joint(Joint::distance(
                &format!("link{k}"),
                BodyRef::Ground,
                on_ground.into(),
                refs[k],
                on_body.into(),
            ));
        }
    }
    b.build().unwrap()
}

fn backend(backend: Backend) -> AugmentedOptions {
    AugmentedOptions {
        backend,
        ..Default::default()
    }
}

#[test]
fn formulations_agree_on_generated_spatial_mechanisms() {
    let mut compared = 0;
    for seed in 1..=40u64 {
        let model = Arc::new(mechanism(seed, seed % 2 == 0));
        let sys: Arc<dyn MultibodySystem> = model.clone();
        let (q, mut v) = model.initial_state();
        let mut rng = Lcg(seed ^ 0x9e37_79b9);
        v.iter_mut().for_each(|x| *x = rng.range(-1.0, 1.0));
        let opts = KinematicOptions::default();
        model.solve_velocities(0.0, &q, &mut v, &opts).unwrap();
        let mut values = model.values();
        model.evaluate(0.0, &q, &v, &mut values);
        let rank = model.analyse_structure(&values, 1e-10).unwrap();
        assert!(
            rank.redundant.is_empty(),
            "seed {seed}: generated mechanism is redundant"
        );
        let formulations: Vec<Box<dyn Formulation>> = vec![
            Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
            Box::new(Augmented::new(sys.clone(), backend(Backend::Tree)).unwrap()),
            Box::new(Augmented::new(sys.clone(), backend(Backend::Dense)).unwrap()),
            Box::new(Embedding::with_defaults(sys.clone())),
            Box::new(Amalgamated::with_defaults(sys.clone())),
        ];
        let (n, m) = (model.layout().n_v(), ConstraintSet::num_equations(model.as_ref()));
        let mut results = Vec::new();
        for mut f in formulations {
            let (mut a, mut lambda) = (vec![0.0; n], vec![0.0; m]);
            f.accelerations(0.0, &q, &v, None, &mut a, &mut lambda)
                .unwrap_or_else(|e| panic!("seed {seed} {}: {e}", f.name()));
            results.push((f.name(), a, lambda));
        }
        let scale = |x: &[f64]| 1.0 + x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (_, a0, l0) = &results[0];
        for (name, a, lambda) in &results[1..] {
            let da = a.iter().zip(a0).fold(0.0f64, |acc, (x, y)| acc.max((x - y).abs())) / scale(a0);
            let dl = lambda.iter().zip(l0).fold(0.0f64, |acc, (x, y)| acc.max((x - y).abs())) / scale(l0);
            assert!(
                da < 1e-9 && dl < 1e-9,
                "seed {seed}: {name} vs augmented: accelerations {da:e}, multipliers {dl:e}"
            );
        }
        // The accelerations satisfy C_q v̇ = Q_d (an independent check on all three).
        let mut cq_a = vec![0.0; m];
        model.jacobian_mul(&values, a0, &mut cq_a);
        let res = cq_a
            .iter()
            .zip(&values.gamma)
            .fold(0.0f64, |acc, (x, g)| acc.max((x - g).abs()));
        assert!(res < 1e-9 * scale(&values.gamma), "seed {seed}: C_q a − Q_d = {res:e}");
        compared += 1;
    }
    assert_eq!(compared, 40);
}
