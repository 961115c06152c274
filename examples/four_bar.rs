//! The four-bar of `shared/anchors`, released from rest and simulated for 10 s with the augmented
//! formulation and RK4 at h = 1 ms. Prints the motion, the reactions at the ground pivots, the
//! statistics, and the state error at t = 1 s against an independent reference (scipy DOP853,
//! rtol = atol = 1e-12, of an index-1 DAE in body coordinates).
//!
//! Run: `cargo run --release --example four_bar`

use dalembert::constraints::{Constraint, Model, Reaction, Revolute};
use dalembert::integrators::{IntegratorOptions, Method, Stabilization};
use dalembert::kinematics::{Body, BodyId, BodyRef, Gravity, Vec2};
use dalembert::system::ConstraintSet as _;
use dalembert::{FormulationKind, Simulation};
use dalembert_testkit::anchors::{state_errors, FOURBAR_1S};
use std::sync::Arc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Pivots A = (0,0), D = (2,0); B = (−1,0); C = (7/6, −√14/3): the elbow-down assembly.
    let (a, b, c) = (
        Vec2::new(0.0, 0.0),
        Vec2::new(-1.0, 0.0),
        Vec2::new(7.0 / 6.0, -(14.0f64).sqrt() / 3.0),
    );
    let d = Vec2::new(2.0, 0.0);
    let rod = |p: Vec2, r: Vec2| {
        let m = (p + r) / 2.0;
        [m.x, m.y, (r - p).y.atan2((r - p).x)]
    };
    let q: Vec<f64> = [rod(a, b), rod(b, c), rod(d, c)].concat();
    let body = |i| BodyRef::Body(BodyId(i));
    let ground = BodyRef::Ground;
    let bodies = vec![
        Body::rod("crank", 1.0, 1.0)?,
        Body::rod("coupler", 2.5, 2.5)?,
        Body::rod("rocker", 1.5, 1.5)?,
    ];
    let joints: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::at("A", [ground, body(0)], a, &q)),
        Box::new(Revolute::at("B", [body(0), body(1)], b, &q)),
        Box::new(Revolute::at("C", [body(1), body(2)], c, &q)),
        Box::new(Revolute::at("D", [ground, body(2)], d, &q)),
    ];
    let model = Arc::new(Model::new(
        bodies,
        vec![Box::new(Gravity::new(Vec2::new(0.0, -9.81)))],
        joints,
    )?);

    let h = 1e-3;
    let mut sim = Simulation {
        model: model.clone().into(),
        qd: vec![0.0; q.len()],
        q,
        start: 0.0,
        end: 10.0,
        formulation: FormulationKind::Augmented,
        redundancy: Default::default(),
        integrator: IntegratorOptions::fixed(Method::rk4(), h, 0.5).with_stabilization(Stabilization::None),
        velocity_weights: None,
        independent: None,
        coordinates: Default::default(),
        inputs: Vec::new(),
        code_forces: Vec::new(),
    };
    sim.assemble()?;

    println!("four-bar (A-B-C-D), released from rest; augmented formulation, RK4, h = {h} s\n");
    println!(
        "{:>5} {:>10} {:>10} {:>10} {:>11} {:>11} {:>12}",
        "t [s]", "crank", "coupler", "rocker", "A.fy [N]", "D.fy [N]", "energy [J]"
    );
    let sys = model.constraints();
    let mut values = sys.values();
    let mut reactions = vec![Reaction::default(); 4];
    let mut at_one = None;
    let stats = sim.run(&mut |s| {
        sys.evaluate(s.t, s.q, s.qd, &mut values);
        sys.reactions(s.q, &values, s.lambda, &mut reactions);
        println!(
            "{:5.2} {:10.5} {:10.5} {:10.5} {:11.4} {:11.4} {:12.9}",
            s.t, s.q[2], s.q[5], s.q[8], reactions[0].force.y, reactions[3].force.y, s.energy
        );
        if (s.t - 1.0).abs() < 1e-12 {
            at_one = Some((s.q.to_vec(), s.qd.to_vec()));
        }
    })?;

    println!(
        "\nsteps {}, evaluations {}, factorizations {}, integration loop {:.1} ms ({:.2} µs/step)",
        stats.steps,
        stats.evaluations,
        stats.factorizations,
        stats.wall_time.as_secs_f64() * 1e3,
        stats.wall_time.as_secs_f64() * 1e6 / stats.steps as f64
    );
    println!(
        "largest |C| = {:.2e} m, largest |Ċ| = {:.2e} m/s, largest energy change = {:.2e} J",
        stats.max_constraint_violation, stats.max_velocity_violation, stats.max_energy_change
    );
    if let Some((q1, qd1)) = at_one {
        let (ep, ev) = state_errors(&q1, &qd1, &FOURBAR_1S);
        let err = ep.max(ev);
        println!("state error at t = 1 s against the independent reference: {err:.2e}");
    }
    Ok(())
}
