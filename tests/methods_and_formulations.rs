//! Every registered integrator ([`METHODS`]) runs on every formulation through the one interface,
//! and they agree on the motion: four-bar with a crank torque, 0.5 s, each method with Baumgarte
//! stabilization (a method that keeps the constraints itself, generalized-α: its own index-3
//! constraint handling, generalized-α and ALI3-P; adaptive methods at rtol 1e-9, atol 1e-11). Final positions agree across formulations
//! to 1e-8 for each method (the formulations' accelerations differ only by round-off, amplified by
//! the run). Projection is not compared here: the augmented formulation projects in the mass metric
//! and the others by coordinate partitioning, two different (both valid) corrections.

use dalembert::integrators::{integrate, Applies, IntegratorOptions, Method, Stabilization, StepControl, METHODS};
use dalembert::{FormulationKind, Simulation};
use dalembert_testkit::mechanisms;

#[test]
fn every_method_runs_on_every_formulation() {
    let mech = mechanisms::four_bar(2.5, 1.0, 5.0, false);
    assert_eq!(METHODS.len(), 5, "a new method: check what this test asserts of it");
    for entry in METHODS {
        let mut method = Method::of(entry);
        if entry.control == StepControl::Adaptive {
            method = method.with("rtol", 1e-9).unwrap().with("atol", 1e-11).unwrap();
        }
        let mut opts = IntegratorOptions::fixed(method, 1e-3, 0.1);
        if !entry.keeps_constraints {
            opts = opts.with_stabilization(Stabilization::Baumgarte);
        }
        let mut finals = Vec::new();
        for kind in FormulationKind::ALL {
            let sim = Simulation {
                model: mech.model.clone().into(),
                q: mech.q.clone(),
                qd: mech.qd.clone(),
                start: 0.0,
                end: 0.5,
                formulation: kind,
                redundancy: Default::default(),
                integrator: opts,
                velocity_weights: None,
                independent: None,
                coordinates: Default::default(),
                inputs: Vec::new(),
                code_forces: Vec::new(),
            };
            let mut f = sim.formulation().unwrap();
            let mut last = Vec::new();
            if entry.applies == Applies::AugmentedIndex3 && kind != FormulationKind::Augmented {
                // Generalized-α and ALI3-P solve the augmented index-3 system themselves: refused, by name, with
                // the other formulations (it would be the augmented method under their names).
                let e = integrate(f.as_mut(), 0.0, 0.5, &sim.q, &sim.qd, &opts, &mut |_| {}).unwrap_err();
                let msg = e.to_string();
                assert!(
                    msg.contains(&format!("the {} formulation has no implicit form", kind.name()))
                        && msg.contains(&format!("use formulation augmented with {}", entry.name)),
                    "{msg}"
                );
                continue;
            }
            let stats = integrate(f.as_mut(), 0.0, 0.5, &sim.q, &sim.qd, &opts, &mut |s| {
                last = s.q.to_vec()
            })
            .unwrap_or_else(|e| panic!("{} on {}: {e}", opts.method.name(), kind.name()));
            if entry.keeps_constraints {
                assert!(
                    stats.max_constraint_violation <= 1e-10,
                    "{} on {}",
                    opts.method.name(),
                    kind.name()
                );
            }
            finals.push(last);
        }
        for other in &finals[1..] {
            let d = other
                .iter()
                .zip(&finals[0])
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(d < 1e-8, "{}: formulations differ by {d:e}", opts.method.name());
        }
    }
}
