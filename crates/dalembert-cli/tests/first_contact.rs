//! What a new user met on first contact (issue #39): outputs over their own input, usage errors
//! that name nothing, `plot`'s column names, numbers printed in 306 digits or as `-0.000000`,
//! errors that do not name the file, `check --redundant`, `inverse` printing before its error.

use std::path::Path;

mod common;
use common::{dalembert, scene, tmp};

/// A copy of a shipped scene in this test's folder (so that a failure cannot harm the original).
fn copy_of(name: &str, as_name: &str) -> std::path::PathBuf {
    let path = tmp(as_name);
    std::fs::copy(scene(name), &path).unwrap();
    path
}

/// The CSV of 0.05 s of `scene_path`, written to `name` in the test folder.
fn simulated(scene_path: &str, name: &str) -> std::path::PathBuf {
    let csv = tmp(name);
    let (ok, _, err) = dalembert(&[
        "simulate",
        scene_path,
        "--end",
        "0.05",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    csv
}

fn refused(args: &[&str], input: &Path) {
    let before = std::fs::read(input).unwrap();
    let (ok, _, err) = dalembert(args);
    assert!(!ok, "{args:?} succeeded");
    assert!(err.contains("the output would overwrite the input"), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert_eq!(std::fs::read(input).unwrap(), before, "{args:?} changed its input");
}

#[test]
fn an_output_that_is_the_input_is_refused_however_spelled() {
    let s = copy_of("slider-crank.toml", "own.toml");
    let p = s.to_str().unwrap();
    let dir = s.parent().unwrap();
    // The same file through `.` and `..`, a symbolic link and a hard link.
    let dotted = dir.join(".").join("..").join(dir.file_name().unwrap()).join("own.toml");
    let symlink = dir.join("own-link.toml");
    let hardlink = dir.join("own-hard.toml");
    let _ = std::fs::remove_file(&symlink);
    let _ = std::fs::remove_file(&hardlink);
    std::os::unix::fs::symlink(&s, &symlink).unwrap();
    std::fs::hard_link(&s, &hardlink).unwrap();
    for out in [&s, &dotted, &symlink, &hardlink] {
        let o = out.to_str().unwrap();
        refused(&["simulate", p, "--end", "0.01", "--output", o], &s);
        refused(&["animate", p, "--end", "0.01", "--output", o], &s);
        refused(&["inverse", p, "--output", o], &s);
        refused(&["sweep", p, "--set", "simulation.end=0.01", "--output", o], &s);
    }
    // plot's output over its CSV, and animate's page over the CSV it replays.
    let csv = simulated(p, "own.csv");
    let c = csv.to_str().unwrap();
    refused(&["plot", c, "--columns", "crank.angle", "--output", c], &csv);
    refused(&["animate", p, "--from", c, "--output", c], &csv);
}

/// Exit 2, one line, naming the argument that is missing.
#[test]
fn missing_arguments_are_named() {
    let sc = scene("slider-crank.toml");
    for (args, names) in [
        (vec!["simulate"], vec!["<SCENE>"]),
        (vec!["sweep", sc.as_str()], vec!["--set"]),
        (vec!["plot", "x.csv"], vec!["--columns", "--output"]),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_dalembert"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        for n in names {
            assert!(err.contains(n), "{args:?} does not name {n}: {err}");
        }
    }
}

#[test]
fn a_mistyped_command_is_suggested_and_no_command_lists_them() {
    let (ok, _, err) = dalembert(&["simulat"]);
    assert!(!ok);
    assert!(
        err.starts_with("error: unknown command 'simulat'; did you mean 'simulate'?"),
        "{err}"
    );
    let (ok, _, err) = dalembert(&[]);
    assert!(!ok);
    for c in ["simulate", "check", "inverse", "plot", "trade", "sweep", "animate"] {
        assert!(
            err.contains(&format!("  {c} ")),
            "plain dalembert does not list {c}: {err}"
        );
    }
}

#[test]
fn plot_lists_the_columns_of_the_file_for_an_unknown_one() {
    let csv = simulated(&scene("pendulum.toml"), "plot-names.csv");
    let svg = tmp("plot-names.svg");
    let (ok, _, err) = dalembert(&[
        "plot",
        csv.to_str().unwrap(),
        "--columns",
        "rod.angel",
        "--output",
        svg.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(!err.contains("scene"), "there is no scene here: {err}");
    assert!(err.contains("no column 'rod.angel' (its columns: t, rod.x,"), "{err}");
    assert!(err.trim_end().ends_with("did you mean 'rod.angle'?"), "{err}");
}

/// A column whose name holds a comma plots (its name is taken whole), beside another one.
#[test]
fn plot_takes_a_column_name_with_a_comma() {
    let text = std::fs::read_to_string(scene("pendulum.toml"))
        .unwrap()
        .replace("name = \"rod\"", "name = \"rod,a\"")
        .replace("[\"ground\", \"rod\"]", "[\"ground\", \"rod,a\"]");
    let path = tmp("comma.toml");
    std::fs::write(&path, text).unwrap();
    let csv = simulated(path.to_str().unwrap(), "comma.csv");
    let svg = tmp("comma.svg");
    let (ok, out, err) = dalembert(&[
        "plot",
        csv.to_str().unwrap(),
        "--columns",
        "rod,a.angle,rod,a.x",
        "--output",
        svg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.starts_with("wrote "), "{out}");
    let page = std::fs::read_to_string(&svg).unwrap();
    assert!(
        page.contains("rod,a.angle") && page.contains("rod,a.x"),
        "both series in the legend"
    );
}

/// Times in messages in shortest form: 5e305, not 306 digits.
#[test]
fn huge_times_print_short() {
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("slider-crank.toml"),
        "--end",
        "1e308",
        "--every",
        "1e307",
        "--step",
        "1e306",
    ]);
    assert!(!ok);
    assert!(err.contains("t = 5e305:"), "{err}");
    assert!(err.len() < 200, "{err}");
}

/// A value that rounds to zero in a table prints without a sign (the slider-crank's slider stays
/// at y = 0 to round-off, either side of it).
#[test]
fn tables_print_no_negative_zero() {
    for args in [
        vec!["simulate".to_string(), scene("slider-crank.toml")],
        vec!["check".to_string(), scene("slider-crank.toml")],
        vec!["inverse".to_string(), scene("driven-four-bar.toml")],
    ] {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, out, err) = dalembert(&refs);
        assert!(ok, "{err}");
        assert!(!out.contains("-0.000"), "{args:?}:\n{out}");
    }
}

#[test]
fn a_step_meaning_trillions_of_steps_is_warned_of_with_its_time() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "simulate",
            &scene("slider-crank.toml"),
            "--step",
            "1e-12",
            "--end",
            "0.0000000001",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.is_empty(), "100 steps: no warning: {err}");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args(["simulate", &scene("slider-crank.toml"), "--step", "1e-12"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufRead::read_line(&mut std::io::BufReader::new(child.stderr.take().unwrap()), &mut first).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        first.starts_with("warning: a step of 1e-12 s over 5e0 s is 5e12 steps, about "),
        "{first}"
    );
    assert!(first.contains("µs per step measured here"), "{first}");
}

/// Write errors name the file: a full device, and a folder that is a file.
#[test]
fn write_errors_name_the_file() {
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("pendulum.toml"),
        "--end",
        "0.05",
        "--output",
        "/dev/full",
    ]);
    assert!(!ok);
    assert!(err.starts_with("error: /dev/full: "), "{err}");
    let csv = simulated(&scene("pendulum.toml"), "write-errors.csv");
    let blocker = tmp("not-a-folder");
    std::fs::write(&blocker, "").unwrap();
    let svg = blocker.join("p.svg");
    let (ok, _, err) = dalembert(&[
        "plot",
        csv.to_str().unwrap(),
        "--columns",
        "rod.angle",
        "--output",
        svg.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.starts_with(&format!("error: {}: ", svg.display())), "{err}");
    assert!(!err.contains("backend error"), "{err}");
}

/// `check --redundant minimum-norm` accepts the redundant parallelogram that plain `check`
/// refuses naming its redundant equations.
#[test]
fn check_takes_redundant() {
    let sc = scene("redundant-parallelogram.toml");
    let text = std::fs::read_to_string(&sc)
        .unwrap()
        .replace("redundant = \"minimum-norm\"", "");
    let plain = tmp("parallelogram-plain.toml");
    std::fs::write(&plain, text).unwrap();
    let p = plain.to_str().unwrap();
    let (ok, _, err) = dalembert(&["check", p]);
    assert!(!ok, "refused without the treatment");
    assert!(err.contains("redundant"), "{err}");
    let (ok, out, err) = dalembert(&["check", p, "--redundant", "minimum-norm"]);
    assert!(ok, "{err}");
    assert!(out.contains("(minimum-norm treatment)"), "{out}");
    let (ok, _, err) = dalembert(&["check", p, "--redundant", "minimum-nrom"]);
    assert!(!ok);
    assert!(err.contains("did you mean 'minimum-norm'?"), "{err}");
}

/// `inverse` on a scene its drivers do not fully drive prints the error only.
#[test]
fn inverse_of_an_undriven_scene_prints_only_its_error() {
    let (ok, out, err) = dalembert(&["inverse", &scene("pendulum.toml")]);
    assert!(!ok);
    assert_eq!(out, "", "nothing on stdout before the error");
    assert!(err.contains("fully driven"), "{err}");
}

/// A sweep with a failed run exits non-zero, the failure in its row and on stderr.
#[test]
fn a_sweep_with_failed_runs_exits_non_zero() {
    let (ok, out, err) = dalembert(&[
        "sweep",
        &scene("slider-crank.toml"),
        "--set",
        "bodies.slider.mass=1,-2",
        "--end",
        "0.05",
    ]);
    assert!(!ok);
    assert!(err.contains("error: 1 of 2 runs failed"), "{err}");
    assert_eq!(out.lines().count(), 3, "header and two rows:\n{out}");
    assert!(out.contains("mass must be finite and non-negative"), "{out}");
}

/// The README's first command: the screen shows the energy balance of its non-conservative model
/// (the motor and the damper did work), which stays put while the energy falls, and the slider's
/// free coordinate `x` rather than its angle, which the prismatic joint holds at 0.
#[test]
fn the_first_screen_shows_that_the_result_is_right() {
    let (ok, out, err) = dalembert(&["simulate", &scene("slider-crank.toml")]);
    assert!(ok, "{err}");
    let header = out.lines().find(|l| l.trim_start().starts_with("t [s]")).unwrap();
    assert!(header.contains("E − W [J]"), "{header}");
    assert!(
        header.contains("slider.x") && !header.contains("slider.angle"),
        "{header}"
    );
    let energy = out.lines().find(|l| l.starts_with("energy ")).unwrap();
    assert!(energy.contains("force 'return-spring', force 'motor'"), "{energy}");
    // "stays within X J of its start": X below 1e-3 J, while E itself moves by 4.6 J.
    let within: f64 = energy
        .split("stays within ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap();
    assert!(within < 1e-3, "{energy}");
    let work: f64 = energy
        .split("did ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap();
    assert!(work.abs() > 1.0, "{energy}");
}

/// A method the formulation cannot take is refused before the CSV is opened: no header-only file
/// is left behind (issue #36, "also found there").
#[test]
fn an_incompatible_method_is_refused_before_the_output_is_opened() {
    let csv = tmp("refused.csv");
    let _ = std::fs::remove_file(&csv);
    let (ok, out, err) = dalembert(&[
        "simulate",
        &scene("pendulum.toml"),
        "--formulation",
        "embedding",
        "--integrator",
        "generalized-alpha",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("generalized-alpha integrates the augmented index-3 equations"),
        "{err}"
    );
    assert_eq!(out, "", "nothing printed before the error");
    assert!(!csv.exists(), "no file written");
}

/// Bricard's loop without `redundant = "minimum-norm"`: the error names the rank deficiency and
/// the setting that runs it.
#[test]
fn a_redundant_loop_gets_the_setting_that_runs_it() {
    let text = std::fs::read_to_string(scene("bricard.toml"))
        .unwrap()
        .replace("redundant = \"minimum-norm\"", "");
    let path = tmp("bricard-plain.toml");
    std::fs::write(&path, text).unwrap();
    let (ok, _, err) = dalembert(&["simulate", path.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("rank deficient (rank 29 of 30)"), "{err}");
    assert!(
        err.contains("set redundant = \"minimum-norm\" in [simulation] (--redundant minimum-norm"),
        "{err}"
    );
    let (ok, _, err) = dalembert(&[
        "simulate",
        path.to_str().unwrap(),
        "--redundant",
        "minimum-norm",
        "--end",
        "0.1",
    ]);
    assert!(ok, "{err}");
}
