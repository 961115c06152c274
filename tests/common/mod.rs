//! Helpers the scene tests share (`mod common;` in each): a run's table and its columns.
// Each test file uses what it needs of these.
#![allow(dead_code)]

use dalembert::energy::EnergyBalance;
use dalembert::output::Table;
use dalembert::Scene;
use std::sync::atomic::AtomicBool;

/// The table of `scene`'s run to its end (the run must finish).
pub fn run(scene: &Scene) -> Table {
    let rec = scene.record(&AtomicBool::new(false));
    rec.outcome.unwrap();
    rec.table
}

/// The largest change of the energy balance `E − W` over `scene`'s run (J;
/// `dalembert::energy::EnergyBalance`, `docs/energy.md`).
pub fn balance_drift(scene: &Scene) -> f64 {
    let model = scene.model.as_system();
    let mut b = EnergyBalance::new(model);
    let mut rows = Vec::new();
    scene.simulation().run(&mut |s| rows.push(b.push(model, s))).unwrap();
    rows.iter().map(|r| (r - rows[0]).abs()).fold(0.0, f64::max)
}

/// The column `name` of `table` (it must exist).
pub fn column(table: &Table, name: &str) -> Vec<f64> {
    table.column(name).unwrap()
}

/// The largest difference between column `name` of two tables of the same samples.
pub fn largest_difference(a: &Table, b: &Table, name: &str) -> f64 {
    let (a, b) = (column(a, name), column(b, name));
    a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// The largest change of entry `k` of `rows` from its first row's.
pub fn largest_change(rows: &[[f64; 4]], k: usize) -> f64 {
    rows.iter().map(|r| (r[k] - rows[0][k]).abs()).fold(0.0, f64::max)
}

/// At each sample of `scene`'s run of planar bodies `(name, mass, inertia)`: their linear
/// momentum `(px, py)`, their angular momentum about the origin, and the run's energy.
pub fn planar_momenta(scene: &Scene, bodies: &[(&str, f64, f64)]) -> Vec<[f64; 4]> {
    let t = run(scene);
    let c = |n: &str| column(&t, n);
    let cols: Vec<_> = bodies
        .iter()
        .map(|(b, m, j)| (["x", "y", "vx", "vy", "omega"].map(|k| c(&format!("{b}.{k}"))), *m, *j))
        .collect();
    let energy = c("energy");
    (0..energy.len())
        .map(|k| {
            let mut out = [0.0, 0.0, 0.0, energy[k]];
            for ([x, y, vx, vy, w], m, j) in &cols {
                out[0] += m * vx[k];
                out[1] += m * vy[k];
                out[2] += m * (x[k] * vy[k] - y[k] * vx[k]) + j * w[k];
            }
            out
        })
        .collect()
}

/// The checks of a strike between free bodies, each run given as rows of invariants with the
/// energy last (as [`planar_momenta`]'s): along `dissipative`, each invariant `k` of `bars`
/// moves less than its bar and the strike takes more than `least_loss` J; `boosted`, the same
/// strike seen from a moving frame, takes the same energy within 1e-8 J; `conservative`, without
/// dissipation and friction, keeps its energy within 1e-8 J. `what` names the case.
pub fn check_strike(
    what: &str,
    [dissipative, boosted, conservative]: [&[[f64; 4]]; 3],
    bars: &[(usize, f64)],
    least_loss: f64,
) {
    for &(k, bar) in bars {
        let off = largest_change(dissipative, k);
        assert!(off < bar, "{what}: momentum {k} moved {off:.3e}");
    }
    let took = |rows: &[[f64; 4]]| rows[0][3] - rows[rows.len() - 1][3];
    let loss = took(dissipative);
    assert!(loss > least_loss, "{what}: the strike took {loss} J");
    let moved = took(boosted);
    assert!((moved - loss).abs() < 1e-8, "{what}: took {moved} J against {loss} J");
    let off = largest_change(conservative, 3);
    assert!(off < 1e-8, "{what}: T + V moved {off:.3e} J");
}
