//! Helpers the scene tests share (`mod common;` in each): a run's table and its columns.
// Each test file uses what it needs of these.
#![allow(dead_code)]

use dalembert::output::Table;
use dalembert::Scene;
use std::sync::atomic::AtomicBool;

/// The table of `scene`'s run to its end (the run must finish).
pub fn run(scene: &Scene) -> Table {
    let rec = scene.record(&AtomicBool::new(false));
    rec.outcome.unwrap();
    rec.table
}

/// The column `name` of `table` (it must exist).
pub fn column(table: &Table, name: &str) -> Vec<f64> {
    table.column(name).unwrap()
}
