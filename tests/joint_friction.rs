//! Joint friction in joint coordinates (`docs/friction.md`, "In joint coordinates") against the
//! same model in absolute coordinates: there the load is the norm of the joint's own multipliers,
//! here the force the joint transmits, from the tree's recursive Newton–Euler pass; two
//! derivations of one law, on every formulation.

mod common;

use common::{column, largest_difference};
use dalembert::Scene;
use std::sync::atomic::AtomicBool;

const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];

/// A spatial chain released horizontal: rod `a` pinned to the ground, rod `b` pinned to `a`
/// (its pin's bodies listed `middle`), and a slider `c` on a prismatic guide along `b`, each
/// joint with friction (pins `μ = 0.3`, `r = 0.05 m`; the guide `μ = 0.2`), integrated in
/// `coordinates` at dopri5 1e-13: the slider runs out along `b` to 22 m at 10 m/s, and at
/// 1e-11 each run's energy is 1.5e-7 J from the run at 1e-13 (integration error, on either side).
fn chain(formulation: &str, coordinates: &str, middle: &str) -> Scene {
    let rod = "mass = 1.0\ninertia = [0.001, 0.08333333333333333, 0.08333333333333333]";
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"a\"\n{rod}\nposition = [0.5, 0.0, 0.0]\n\
         [[bodies]]\nname = \"b\"\n{rod}\nposition = [1.5, 0.0, 0.0]\n\
         [[bodies]]\nname = \"c\"\nmass = 0.5\ninertia = [0.002, 0.003, 0.004]\nposition = [1.8, 0.0, 0.0]\n\
         [[joints]]\nname = \"p1\"\ntype = \"revolute\"\nbodies = [\"ground\", \"a\"]\nat = [0.0, 0.0, 0.0]\n\
         axis = [0.0, -1.0, 0.0]\nfriction = {{ coefficient = 0.3, radius = 0.05 }}\n\
         [[joints]]\nname = \"p2\"\ntype = \"revolute\"\nbodies = {middle}\nat = [1.0, 0.0, 0.0]\n\
         axis = [0.0, -1.0, 0.0]\nfriction = {{ coefficient = 0.3, radius = 0.05 }}\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"b\", \"c\"]\nat = [1.8, 0.0, 0.0]\n\
         axis = [1.0, 0.0, 0.0]\nfriction = {{ coefficient = 0.2 }}\n\
         [simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"dopri5\"\n\
         rtol = 1e-13\natol = 1e-13\noutput_every = 0.01\ncoordinates = \"{coordinates}\"\n"
    );
    Scene::from_toml(&text, "chain with friction").unwrap()
}

#[test]
fn friction_in_joint_coordinates_moves_a_chain_as_in_absolute_coordinates() {
    // Each joint's value, friction and reaction, and the energy, within 1e-8 of each column's
    // scale (both at dopri5 1e-13; the energy measured 1.4e-9 J apart of 4.9 J), with the
    // middle pin's bodies listed either way (its value, row and friction then turn sign: the
    // tree's coordinate is read with that sign), on every formulation; the same stick and slip
    // events in both.
    for middle in ["[\"a\", \"b\"]", "[\"b\", \"a\"]"] {
        for formulation in FORMULATIONS {
            let record = |coordinates: &str| {
                let rec = chain(formulation, coordinates, middle).record(&AtomicBool::new(false));
                let stats = rec.outcome.unwrap();
                (rec.table, stats.events)
            };
            let (absolute, events) = record("absolute");
            let (joint, joint_events) = record("joint");
            assert!(
                events >= 4,
                "{formulation} {middle}: {events} events, expected stick and slip"
            );
            assert_eq!(events, joint_events, "{formulation} {middle}: events");
            for name in [
                "p1.q",
                "p2.q",
                "guide.q",
                "p1.friction",
                "p2.friction",
                "guide.friction",
                "p1.fx",
                "p1.fz",
                "p2.fx",
                "p2.fz",
                "guide.fy",
                "guide.fz",
                "guide.mx",
                "energy",
            ] {
                let scale = column(&absolute, name).iter().fold(1.0f64, |s, x| s.max(x.abs()));
                let worst = largest_difference(&joint, &absolute, name);
                assert!(
                    worst < 1e-8 * scale,
                    "{formulation} {middle} {name}: joint coordinates {worst:e} from absolute ones (scale {scale})"
                );
            }
        }
    }
}

/// A generated spatial chain of 3 to 5 links (seeded): each joint revolute or prismatic on a
/// random axis through a point near the chain's line, its two bodies listed either way, with
/// friction (pins `μ` 0.1–0.4 and `r` 0.02–0.08 m, guides `μ` 0.1–0.4), some with limits
/// (`e` 0.3 on a pin, a plastic stop on a guide); released from rest under gravity.
fn generated_chain(seed: u64, formulation: &str, coordinates: &str) -> String {
    let mut rng = dalembert_testkit::fuzz::Rng::new(seed);
    let mut unit = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let links = 3 + (unit() * 3.0) as usize;
    let mut text = String::from("[scene]\ngravity = [0.0, 0.0, -9.81]\n");
    for k in 0..links {
        let (mass, a, b, c) = (
            0.5 + unit(),
            0.02 + 0.02 * unit(),
            0.02 + 0.02 * unit(),
            0.02 + 0.02 * unit(),
        );
        text += &format!(
            "[[bodies]]\nname = \"l{k}\"\nmass = {mass}\ninertia = [{a}, {b}, {c}]\nposition = [{}, 0.0, 0.0]\n",
            k as f64 + 0.5
        );
    }
    for k in 0..links {
        let parent = if k == 0 {
            "ground".to_string()
        } else {
            format!("l{}", k - 1)
        };
        let child = format!("l{k}");
        let bodies = if unit() < 0.5 {
            format!("[\"{parent}\", \"{child}\"]")
        } else {
            format!("[\"{child}\", \"{parent}\"]")
        };
        let axis = [unit() - 0.5, unit() - 0.5, unit() - 0.5];
        let (y, z) = (0.1 * (unit() - 0.5), 0.1 * (unit() - 0.5));
        let prismatic = k > 0 && unit() < 0.3;
        let mu = 0.1 + 0.3 * unit();
        let (kind, friction, limits) = if prismatic {
            let stop = (unit() < 0.5).then_some("limits = [-0.3, 0.3]\nrestitution = 0.0\n");
            ("prismatic", format!("{{ coefficient = {mu} }}"), stop.unwrap_or(""))
        } else {
            let stop = (unit() < 0.5).then_some("limits = [-1.0, 1.0]\nrestitution = 0.3\n");
            (
                "revolute",
                format!("{{ coefficient = {mu}, radius = {} }}", 0.02 + 0.06 * unit()),
                stop.unwrap_or(""),
            )
        };
        text += &format!(
            "[[joints]]\nname = \"j{k}\"\ntype = \"{kind}\"\nbodies = {bodies}\nat = [{k}.0, {y}, {z}]\n\
             axis = [{}, {}, {}]\nfriction = {friction}\n{limits}",
            axis[0], axis[1], axis[2]
        );
    }
    text += &format!(
        "[simulation]\nend = 1.0\nformulation = \"{formulation}\"\nintegrator = \"dopri5\"\n\
         rtol = 1e-12\natol = 1e-12\noutput_every = 0.01\ncoordinates = \"{coordinates}\"\n"
    );
    text
}

#[test]
fn generated_chains_with_friction_and_stops_move_alike_in_joint_and_absolute_coordinates() {
    // 37 generated chains (`generated_chain`, seeds 0–35 and 107, the formulation by seed), each in
    // joint and in absolute coordinates at dopri5 1e-12: every joint's value, rate, friction and
    // stop force and the energy within 1e-8 of each column's scale (measured 1.4e-10 at worst),
    // with the same number of events (2 to 34: stick, slip, impacts, stops held and let go).
    // Three of them found a stop passed unseen. Seeds 0 and 9: a rod rebounding slowly off its
    // stop came back onto it within one step, its event function just below zero from the
    // impact's location on; the rebound now raises it to above zero (`Frictional::leave_bound`).
    // Seed 32: two stops a chain rests near struck one after the other ever faster (each strike
    // drove the other in), and a third, let go in one of those impacts, kept a function below
    // zero, so the step that crossed the next stop was taken whole; now the others at their
    // bounds are held through an impact where it would drive them in, and a stop let go is
    // raised too. Seed 107 (amalgamated): a step shortened for a stop's crossing on its dense
    // output ended 6.7e-6 rad short of the stop (the interpolant of a step whose law changed
    // inside it) and the stop was struck there all the same, 1.5e-4 s early; the aimed function
    // now counts only where the step fell short by round-off (`AIMED_SLACK` in the driver).
    for seed in (0..36u64).chain([107]) {
        let formulation = FORMULATIONS[seed as usize % 3];
        let run = |coordinates: &str| {
            let scene = Scene::from_toml(&generated_chain(seed, formulation, coordinates), "generated").unwrap();
            let rec = scene.record(&AtomicBool::new(false));
            let stats = rec.outcome.unwrap();
            (rec.table, stats.events)
        };
        let (absolute, events) = run("absolute");
        let (joint, joint_events) = run("joint");
        // The same events, except on seed 107: there the step shortened for the stop that its
        // interpolant put too early counts as one more step ended at an event (the stop is then
        // struck in the next step, where it is).
        if seed != 107 {
            assert_eq!(events, joint_events, "seed {seed} ({formulation}): events");
        }
        // No stop is passed, in either (by more than 1e-9 rad or m: the location's round-off).
        let text = generated_chain(seed, formulation, "absolute");
        for block in text.split("[[joints]]").skip(1) {
            let name = block.split('"').nth(1).unwrap();
            let bound = match block {
                b if b.contains("limits = [-1.0, 1.0]") => 1.0,
                b if b.contains("limits = [-0.3, 0.3]") => 0.3,
                _ => continue,
            };
            for table in [&absolute, &joint] {
                let beyond = column(table, &format!("{name}.q"))
                    .iter()
                    .fold(0.0f64, |m, q| m.max(q.abs() - bound));
                assert!(
                    beyond < 1e-9,
                    "seed {seed} ({formulation}): {name} passed its stop by {beyond:e}"
                );
            }
        }
        for name in &absolute.columns {
            let compared = [".q", ".qd", ".friction", ".limit"].iter().any(|e| name.ends_with(e)) || name == "energy";
            if !compared {
                continue;
            }
            let scale = column(&absolute, name).iter().fold(1.0f64, |s, x| s.max(x.abs()));
            let worst = largest_difference(&joint, &absolute, name);
            assert!(
                worst < 1e-8 * scale,
                "seed {seed} ({formulation}) {name}: joint coordinates {worst:e} from absolute ones (scale {scale})"
            );
        }
    }
}
