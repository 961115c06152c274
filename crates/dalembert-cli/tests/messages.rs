//! Messages that used to mislead: the step actually taken, flags the method ignores, a trade grid
//! with a zero step.

mod common;
use common::{dalembert, scene, tmp};

#[test]
fn the_summary_states_the_step_actually_taken() {
    // A fixed step never exceeds the output interval: 5 s becomes 100 steps of 0.01 s.
    let (ok, out, err) = dalembert(&["simulate", &scene("pendulum.toml"), "--step", "5", "--end", "1"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("step 1e-2 s (asked 5e0 s: a whole number of steps spans each output interval of 1e-2 s)"),
        "{out}"
    );
    assert!(out.contains("statistics   100 steps"), "{out}");
    // A step that does not divide the interval: 3e-3 s into 1e-2 s is taken as 2.5e-3 s.
    let (ok, out, _) = dalembert(&["simulate", &scene("pendulum.toml"), "--step", "3e-3", "--end", "0.1"]);
    assert!(ok && out.contains("step 2.5e-3 s (asked 3e-3 s"), "{out}");
}

#[test]
fn flags_the_method_ignores_are_named() {
    let (ok, _, err) = dalembert(&["simulate", &scene("pendulum.toml"), "--end", "0.1", "--rtol", "1e-3"]);
    assert!(ok);
    assert_eq!(err, "warning: --rtol applies to dopri5 only; ignored with rk4\n");
}

#[test]
fn a_trade_grid_with_a_zero_step_is_refused() {
    let out = tmp("trade-zero");
    let (ok, _, err) = dalembert(&[
        "trade",
        &scene("pendulum.toml"),
        "--steps",
        "0",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert_eq!(err, "error: --steps: every value must be positive and finite, got 0\n");
    assert!(!out.join("trade.csv").exists(), "no rows written");
}
