//! Redundant but consistent constraints from a scene and the command line: the shipped
//! parallelogram with a third crank runs with `redundant = "minimum-norm"` on every formulation and
//! follows the exact one-degree-of-freedom reduction; without the treatment the run stops naming
//! the equations.
//!
//! Reduction (derived for this test): the three cranks (uniform rods, m = 1 kg, L = 1 m, pivots on
//! the x axis) turn by the same angle φ and the coupler (2 kg) translates with the crank tips, so
//! T = ½ (3 · m L²/3 + m_c L²) φ̇² = 3/2 φ̇² and V = (3 m L/2 + m_c L) g sin φ = 7/2 g sin φ:
//! 3 φ̈ = −7/2 g cos φ.

mod common;
use common::{dalembert, scene, tmp};

const G: f64 = 9.81;

/// φ(t) of the reduction by RK4 at h = 1e-5 (error ≈ 1e-16 over 1 s).
fn reduced_angle(phi0: f64, t_end: f64) -> f64 {
    let f = |y: [f64; 2]| [y[1], -(3.5 / 3.0) * G * y[0].cos()];
    let steps = (t_end / 1e-5).round() as usize;
    let h = t_end / steps as f64;
    let mut y = [phi0, 0.0];
    for _ in 0..steps {
        let k1 = f(y);
        let k2 = f([y[0] + 0.5 * h * k1[0], y[1] + 0.5 * h * k1[1]]);
        let k3 = f([y[0] + 0.5 * h * k2[0], y[1] + 0.5 * h * k2[1]]);
        let k4 = f([y[0] + h * k3[0], y[1] + h * k3[1]]);
        for i in 0..2 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    y[0]
}

#[test]
fn the_redundant_parallelogram_follows_its_reduction_with_every_formulation() {
    for formulation in ["augmented", "embedding", "amalgamated"] {
        let csv = tmp(&format!("par-{formulation}.csv"));
        let (ok, _, err) = dalembert(&[
            "simulate",
            &scene("redundant-parallelogram.toml"),
            "--formulation",
            formulation,
            "--end",
            "1",
            "--output",
            csv.to_str().unwrap(),
        ]);
        assert!(ok, "{formulation}: {err}");
        let mut rdr = csv::Reader::from_path(&csv).unwrap();
        let header = rdr.headers().unwrap().clone();
        let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
        let (first, last) = (&rows[0], &rows[rows.len() - 1]);
        // From the assembled initial angle (the file's numbers are rounded to 7 digits).
        let a = header.iter().position(|h| h == "crank-a.angle").unwrap();
        let exact = reduced_angle(first[a].parse().unwrap(), 1.0);
        for crank in ["crank-a", "crank-e", "crank-d"] {
            let k = header.iter().position(|h| h == format!("{crank}.angle")).unwrap();
            let phi: f64 = last[k].parse().unwrap();
            // RK4 at 1 ms with projection on this smooth motion: errors far below 1e-9.
            assert!((phi - exact).abs() < 1e-9, "{formulation} {crank}: {phi} vs {exact}");
        }
        // The coupler translates: its angle stays zero.
        let k = header.iter().position(|h| h == "coupler.angle").unwrap();
        assert!(last[k].parse::<f64>().unwrap().abs() < 1e-9);
    }
}

#[test]
fn without_the_treatment_the_redundancy_is_named() {
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("redundant-parallelogram.toml"),
        "--redundant",
        "error",
        "--end",
        "0.1",
    ]);
    assert!(!ok && err.contains("rank deficient (rank 11 of 12)"), "{err}");
    let (ok, out, err) = dalembert(&["check", &scene("redundant-parallelogram.toml")]);
    assert!(
        ok && out.contains("redundant    'F' (y) (minimum-norm treatment)"),
        "{out}{err}"
    );
    let (ok, _, err) = dalembert(&[
        "simulate",
        &scene("redundant-parallelogram.toml"),
        "--redundant",
        "some",
    ]);
    assert!(
        !ok && err.contains("unknown redundancy treatment 'some' (expected error, minimum-norm)"),
        "{err}"
    );
}
