//! The `dalembert` command end to end: exit codes, summaries, the CSV columns, plots.

mod common;
use common::{dalembert, scene, tmp};

#[test]
fn simulate_writes_the_documented_csv_columns() {
    let csv = tmp("sc.csv");
    let (ok, out, err) = dalembert(&[
        "simulate",
        &scene("slider-crank.toml"),
        "--end",
        "0.2",
        "--every",
        "0.05",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains("1 degree(s) of freedom") && out.contains("statistics") && out.contains("largest |C|"),
        "{out}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let expected_start = [
        "t",
        "crank.x",
        "crank.y",
        "crank.angle",
        "crank.vx",
        "crank.vy",
        "crank.omega",
    ];
    assert_eq!(&header[..7], &expected_start);
    for col in [
        "O.fx",
        "O.fy",
        "guide.fx",
        "guide.fy",
        "guide.torque",
        "energy",
        "constraint_violation",
        "velocity_violation",
    ] {
        assert!(header.contains(&col), "missing {col} in {header:?}");
    }
    assert!(
        !header.contains(&"O.torque"),
        "a revolute joint carries no torque column"
    );
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(rows.len(), 5, "t = 0, 0.05, …, 0.2");
    for r in rows {
        assert_eq!(r.split(',').count(), header.len());
        assert!(
            r.split(',')
                .all(|v| v.parse::<f64>().map(f64::is_finite).unwrap_or(false)),
            "{r}"
        );
    }
}

#[test]
fn flags_override_the_scene() {
    let (ok, out, err) = dalembert(&[
        "simulate",
        &scene("pendulum.toml"),
        "--formulation",
        "embedding",
        "--integrator",
        "dopri5",
        "--rtol",
        "1e-9",
        "--stabilization",
        "none",
        "--end",
        "0.5",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("embedding formulation, dopri5 (rtol 1e-9"), "{out}");
    assert!(out.contains("constraints: none"), "{out}");
}

#[test]
fn check_reports_and_fails_on_redundancy() {
    let (ok, out, _) = dalembert(&["check", &scene("four-bar.toml")]);
    assert!(
        ok && out.contains("1 degree(s) of freedom") && out.contains("initial reactions"),
        "{out}"
    );
    let redundant = tmp("redundant.toml");
    let text = std::fs::read_to_string(scene("four-bar.toml")).unwrap()
        + "\n[[joints]]\nname = \"extra\"\ntype = \"revolute\"\nbodies = [\"ground\", \"crank\"]\nat = [0.0, 0.0]\n";
    std::fs::write(&redundant, text).unwrap();
    let (ok, out, err) = dalembert(&["check", redundant.to_str().unwrap()]);
    assert!(!ok, "redundant scene must fail: {out}");
    assert!(err.contains("redundant") && err.lines().count() == 1, "{err}");
}

#[test]
fn bad_scene_is_one_line_and_non_zero() {
    let bad = tmp("bad.toml");
    std::fs::write(
        &bad,
        "[[bodies]]\nname = \"a\"\nmass = -1.0\ninertia = 0.1\nposition = [0.0, 0.0]\n",
    )
    .unwrap();
    let (ok, _, err) = dalembert(&["simulate", bad.to_str().unwrap()]);
    assert!(!ok);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("body 'a'") && err.contains("mass"), "{err}");
    let (ok, _, err) = dalembert(&["simulate", "no-such-file.toml"]);
    assert!(!ok && err.contains("no-such-file.toml"), "{err}");
}

#[test]
fn inverse_prints_driver_efforts() {
    let csv = tmp("inv.csv");
    let (ok, out, err) = dalembert(&[
        "inverse",
        &scene("driven-four-bar.toml"),
        "--end",
        "0.5",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("motor.effort"), "{out}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.lines().next().unwrap().contains("motor.effort"));
    // An under-driven scene is refused with the reason.
    let (ok, _, err) = dalembert(&["inverse", &scene("four-bar.toml")]);
    assert!(!ok && err.contains("degrees of freedom"), "{err}");
}

#[test]
fn plot_writes_an_svg() {
    let csv = tmp("p.csv");
    let svg = tmp("p.svg");
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("pendulum.toml"),
        "--end",
        "1",
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (ok, out, err) = dalembert(&[
        "plot",
        csv.to_str().unwrap(),
        "--columns",
        "rod.angle,rod.omega",
        "--output",
        svg.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("wrote"));
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.starts_with("<svg") && text.contains("rod.angle") && text.contains("polyline"),
        "{}",
        &text[..200.min(text.len())]
    );
    let (ok, _, err) = dalembert(&[
        "plot",
        csv.to_str().unwrap(),
        "--columns",
        "nope",
        "--output",
        svg.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("no column 'nope'"), "{err}");
}

/// A narrowed grid: the files are written, every run is recorded, and RK4's error falls by about
/// 2⁴ when the step halves (its order; the reference is Dormand–Prince at 1e-12).
#[test]
fn trade_measures_a_narrowed_grid() {
    let dir = tmp("trade");
    let (ok, out, err) = dalembert(&[
        "trade",
        &scene("pendulum.toml"),
        "--end",
        "1",
        "--formulations",
        "augmented",
        "--integrators",
        "rk4,dopri5",
        "--stabilizations",
        "none",
        "--steps",
        "2e-2,1e-2",
        "--tolerances",
        "1e-6",
        "--output",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("best method per accuracy band"), "{out}");
    let csv = std::fs::read_to_string(dir.join("trade.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 3);
    let err_of = |h: &str| -> f64 {
        rows.iter().find(|r| r[0] == "augmented/rk4/none" && r[1] == h).unwrap()[4]
            .parse()
            .unwrap()
    };
    let ratio = err_of("0.02") / err_of("0.01");
    assert!((10.0..=24.0).contains(&ratio), "RK4 error ratio {ratio}");
    assert!(std::fs::read_to_string(dir.join("work-precision.svg"))
        .unwrap()
        .starts_with("<svg"));
    assert!(std::fs::read_to_string(dir.join("trade.md")).unwrap().contains("★"));
}
