//! A conservative model's energy is a first integral: a run that changes it by more than 1 % of
//! the energy scale is flagged on stderr (`--strict`: an error), an accurate run is not.

use std::process::Command;

fn simulate(args: &[&str]) -> (Option<i32>, String) {
    let scene = format!("{}/../../scenes/chain-8.toml", env!("CARGO_MANIFEST_DIR"));
    let out = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args(["simulate", &scene, "--end", "10"])
        .args(args)
        .output()
        .unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into())
}

#[test]
fn a_blow_up_is_not_silent() {
    // Semi-implicit Euler with projection at 1 ms gains thousands of joules on the chain of 8
    // (docs/robustness.md): the exact motion keeps T + V = 0.
    let (code, err) = simulate(&["--integrator", "symplectic-euler"]);
    assert_eq!(code, Some(0));
    assert!(
        err.starts_with("warning: the energy of this conservative model changed by"),
        "{err}"
    );
    let (code, err) = simulate(&["--integrator", "symplectic-euler", "--strict"]);
    assert_eq!(code, Some(1));
    assert!(
        err.starts_with("error: the energy of this conservative model changed by"),
        "{err}"
    );
}

#[test]
fn an_accurate_run_is_not_flagged() {
    let (code, err) = simulate(&["--strict"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.is_empty(), "{err}");
}
