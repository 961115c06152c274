//! Coordinate partitioning (embedding formulation + projection after every step) through the
//! integrators: constraints held to the Newton tolerance, the same motion as the augmented
//! formulation, and automatic re-partitioning when the chosen dependent block becomes singular.

use dalembert::augmented::Augmented;
use dalembert::embedding::{Embedding, EmbeddingOptions};
use dalembert::integrators::{integrate, IntegratorOptions, Method, Stabilization, Statistics};
use dalembert::system::Formulation;
use dalembert_testkit::mechanisms::{self, Mechanism};

fn run(f: &mut dyn Formulation, mech: &Mechanism, t_end: f64, opts: &IntegratorOptions) -> (Vec<f64>, Statistics) {
    let mut last = Vec::new();
    let stats = integrate(f, 0.0, t_end, &mech.q, &mech.qd, opts, &mut |s| last = s.q.to_vec()).unwrap();
    (last, stats)
}

/// Four-bar for 5 s, RK4 at 1 ms: coordinate partitioning keeps |C| and |Ċ| at the 1e-10 Newton
/// tolerance after every step, and the crank follows the augmented+projection run within 1e-7
/// (both are 4th-order approximations of the same motion, each ≈ 1e-9 from it; chaos-free here).
#[test]
fn four_bar_coordinate_partitioning_holds_constraints_and_motion() {
    let mech = mechanisms::four_bar(std::f64::consts::PI, 0.0, 0.0, false);
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.1)
        .with_stabilization(Stabilization::Projection { tolerance: 1e-10 });
    let (q_cp, s_cp) = run(&mut Embedding::with_defaults(mech.model.clone()), &mech, 5.0, &opts);
    let (q_aug, _) = run(
        &mut Augmented::with_defaults(mech.model.clone()).unwrap(),
        &mech,
        5.0,
        &opts,
    );
    assert!(
        s_cp.max_constraint_violation <= 1e-10,
        "{}",
        s_cp.max_constraint_violation
    );
    assert!(s_cp.max_velocity_violation <= 1e-10, "{}", s_cp.max_velocity_violation);
    let d = q_cp.iter().zip(&q_aug).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(d < 1e-7, "coordinate partitioning vs augmented: {d:e}");
}

/// A rod pendulum whirling round its pivot, with the user's choice of `x` as the independent
/// coordinate: `C_qd` (columns y, θ) is singular whenever the rod is horizontal, so the formulation
/// must re-partition, log it with its time, and keep the motion of the augmented formulation.
#[test]
fn whirling_pendulum_forces_repartitioning() {
    let mech = mechanisms::chain(1.0, 1.0, &[-0.5], &[8.0], &[]);
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.05)
        .with_stabilization(Stabilization::Projection { tolerance: 1e-11 });
    let mut emb = Embedding::new(
        mech.model.clone(),
        EmbeddingOptions {
            independent: Some(vec![0]),
            ..Default::default()
        },
    );
    let (q_cp, stats) = run(&mut emb, &mech, 2.0, &opts);
    let (q_aug, _) = run(
        &mut Augmented::with_defaults(mech.model.clone()).unwrap(),
        &mech,
        2.0,
        &opts,
    );
    assert!(stats.repartitions >= 1, "no re-partition");
    let log = emb.repartitions();
    // The first LOGGED_REPARTITIONS are logged with their coordinates, all are counted.
    let logged = stats
        .repartitions
        .min(dalembert::system::partition::LOGGED_REPARTITIONS as u64);
    assert_eq!(log.len() as u64, logged);
    assert_eq!(log[0].old, vec![0]);
    assert!(log[0].time > 0.0 && log[0].time < 2.0);
    let d = q_cp.iter().zip(&q_aug).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(d < 1e-7, "motion differs by {d:e}");
}

/// The scene key `independent` reaches the embedding's partition. A horizontal chain of 64 links
/// (the anchors' chain), 5 s, RK4 at 1 ms with coordinate partitioning: the automatic full-pivot
/// partition at the horizontal start takes some link angles as dependent, `C_qd` degrades and the
/// run loses 0.66 J of energy (docs/trade.md, measured through the API's
/// `EmbeddingOptions::independent`: 0.66 J against 1.6e-3 J with the link angles named). From a
/// scene that names the 64 link angles the energy change stays below 1e-2 J; without the key it
/// exceeds 0.1 J.
#[test]
fn scene_key_independent_names_the_partition() {
    use dalembert::{FormulationKind, Scene};
    let n = 64;
    let mut text = String::from("[scene]\ngravity = [0.0, -9.81]\n");
    for k in 0..n {
        let first = if k == 0 {
            "ground".to_string()
        } else {
            format!("link{}", k - 1)
        };
        text += &format!(
            "[[bodies]]\nname = \"link{k}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [{}, 0.0]\n",
            k as f64 + 0.5
        );
        text += &format!(
            "[[joints]]\nname = \"J{k}\"\ntype = \"revolute\"\nbodies = [\"{first}\", \"link{k}\"]\nat = [{k}.0, 0.0]\n"
        );
    }
    text += "[simulation]\nend = 5.0\nformulation = \"embedding\"\n";
    let angles: Vec<String> = (0..n).map(|k| format!("\"link{k}.angle\"")).collect();
    let named = format!("{text}independent = [{}]\n", angles.join(", "));
    let energy = |toml: &str| {
        let scene = Scene::from_toml(toml, "chain").unwrap();
        assert_eq!(scene.settings.formulation, FormulationKind::Embedding);
        scene.simulation().run(&mut |_| {}).unwrap().max_energy_change
    };
    let (with_key, without) = (energy(&named), energy(&text));
    assert!(with_key < 1e-2, "named link angles: energy change {with_key:e} J");
    assert!(without > 0.1, "automatic partition: energy change {without:e} J");
}
