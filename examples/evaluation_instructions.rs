//! `N` evaluations of one formulation on one model, to count their instructions under callgrind:
//! a measure of an evaluation's cost that does not depend on the machine's load (criterion's times
//! on this 2-core machine differ by up to 40 % between two runs of the same code).
//!
//! ```text
//! cargo build --release --example evaluation_instructions
//! ir() { valgrind --tool=callgrind --callgrind-out-file=/dev/null "$@" 2>&1 | grep -o "Collected : [0-9]*" | grep -o "[0-9]*"; }
//! b=target/release/examples/evaluation_instructions
//! echo $(( ($(ir $b four-bar embedding 1010) - $(ir $b four-bar embedding 10)) / 1000 ))   # per evaluation
//! ```
//!
//! Models: a scene of `scenes/` by name, or `chain-N` (N rods hanging at −0.3 rad, turning);
//! formulations `augmented`, `embedding`, `amalgamated`.
use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::system::Formulation;
use std::hint::black_box;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let Some((scene, kind, n)) = (a.len() == 4).then(|| (&a[1], a[2].as_str(), a[3].parse::<usize>())) else {
        eprintln!("usage: evaluation_instructions MODEL FORMULATION N (e.g. four-bar embedding 1000)");
        std::process::exit(2);
    };
    let n = n.expect("N: a count of evaluations");
    let (sys, q, qd) = if let Some(k) = scene.strip_prefix("chain-") {
        let k: usize = k.parse().unwrap();
        let m = dalembert_testkit::mechanisms::chain(1.0, 1.0, &vec![-0.3; k], &vec![0.1; k], &[]);
        (
            m.model.clone() as std::sync::Arc<dyn dalembert::system::MultibodySystem>,
            m.q,
            m.qd,
        )
    } else {
        let s = dalembert::Scene::from_path(format!("scenes/{scene}.toml")).unwrap();
        (s.model.system(), s.q.clone(), s.qd.clone())
    };
    let mut f: Box<dyn Formulation> = match kind {
        "embedding" => Box::new(Embedding::with_defaults(sys.clone())),
        "amalgamated" => Box::new(Amalgamated::with_defaults(sys.clone())),
        _ => Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
    };
    let (mut qdd, mut lam) = (vec![0.0; qd.len()], vec![0.0; sys.num_equations()]);
    for k in 0..n {
        f.accelerations(
            1e-12 * (k + 1) as f64,
            black_box(&q),
            black_box(&qd),
            None,
            &mut qdd,
            &mut lam,
        )
        .unwrap();
    }
    black_box(&qdd);
}
