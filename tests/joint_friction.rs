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
