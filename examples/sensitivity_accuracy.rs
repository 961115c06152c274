//! The accuracy and cost of a run's sensitivities against the parameter change `δ` and the step
//! (docs/sensitivities.md): the slider of `tests/data/hanging-spring.toml` over 1 s, whose motion
//! has a closed form, differentiated in its stiffness, damping and mass; and the cost of each
//! parameter on the shipped four-bar and spatial chain of 16 (absolute coordinates).
//!
//! ```text
//! cargo run --release --example sensitivity_accuracy
//! ```

use dalembert::{Scene, SceneValue, SensitivityRequest};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

const G: f64 = 9.81;

fn slider_y(t: f64, m: f64, k: f64, c: f64) -> f64 {
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let ue = -m * G / k;
    -1.0 + ue * (1.0 - (-zeta * w * t).exp() * ((wd * t).cos() + zeta * w / wd * (wd * t).sin()))
}

fn derivative(f: impl Fn(f64) -> f64, x: f64) -> f64 {
    let h = 1e-3 * x;
    let d = |h: f64| (f(x + h) - f(x - h)) / (2.0 * h);
    (4.0 * d(h / 2.0) - d(h)) / 3.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let base = Scene::from_path("tests/data/hanging-spring.toml")?;
    let params = ["forces.spring.stiffness", "forces.spring.damping", "bodies.slider.mass"];
    let (m, k, c) = (2.0, 400.0, 4.0);
    println!(
        "hanging spring, 1 s: largest error of d(slider.y)/dp against the closed form, relative to its largest value"
    );
    println!(
        "{:>10} {:>8} {:>10} {:>10} {:>10} {:>10}",
        "method", "step", "δ / p", "k", "c", "m"
    );
    for (method, step) in [("rk4", 1e-3), ("rk4", 1e-4), ("dopri5", 1e-3), ("ali3-p", 1e-4)] {
        for relative in [1e-7, 1e-6, 1e-5, 1e-4, 1e-3] {
            let scene = base.with_values(&[
                ("simulation.end", SceneValue::Number(1.0)),
                ("simulation.output_every", SceneValue::Number(0.01)),
                ("simulation.integrator", method.into()),
                ("simulation.step", SceneValue::Number(step)),
                ("simulation.rtol", SceneValue::Number(1e-10)),
                ("simulation.atol", SceneValue::Number(1e-12)),
            ])?;
            let mut request = SensitivityRequest::new(&params, &["slider.y"]);
            request.relative_change = relative;
            let run = scene.sensitivities(&request, &AtomicBool::new(false))?;
            let t = run.table.column("t").unwrap_or_default();
            let mut errors = Vec::new();
            for (j, p) in params.iter().enumerate() {
                let got = run.sensitivity("slider.y", p).unwrap_or_default();
                let want: Vec<f64> = t
                    .iter()
                    .map(|&t| match j {
                        0 => derivative(|k| slider_y(t, m, k, c), k),
                        1 => derivative(|c| slider_y(t, m, k, c), c),
                        _ => derivative(|m| slider_y(t, m, k, c), m),
                    })
                    .collect();
                let scale = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let err = got.iter().zip(&want).fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
                errors.push(err / scale);
            }
            println!(
                "{method:>10} {step:>8.0e} {relative:>10.0e} {:>10.2e} {:>10.2e} {:>10.2e}",
                errors[0], errors[1], errors[2]
            );
        }
    }
    println!();
    println!("cost: wall time of the run (best of 11) with 0, 1 and 2 parameters");
    for (path, end, settings) in [
        ("scenes/four-bar.toml", 10.0, vec![]),
        (
            "scenes/spatial-chain-16.toml",
            2.0,
            vec![("simulation.coordinates", SceneValue::from("absolute"))],
        ),
    ] {
        let mut values = vec![("simulation.end", SceneValue::Number(end))];
        values.extend(settings);
        let scene = Scene::from_path(path)?.with_values(&values)?;
        let names = scene.model.body_names();
        let masses: Vec<String> = names.iter().take(2).map(|b| format!("bodies.{b}.mass")).collect();
        // Best of 11, the three counts interleaved so that a slow spell of the machine falls on
        // all of them alike.
        let mut times = [f64::INFINITY; 3];
        for _ in 0..11 {
            for (count, best) in times.iter_mut().enumerate() {
                let started = Instant::now();
                if count == 0 {
                    scene.record(&AtomicBool::new(false)).outcome?;
                } else {
                    let p: Vec<&str> = masses[..count].iter().map(String::as_str).collect();
                    scene
                        .sensitivities(&SensitivityRequest::new(&p, &[]), &AtomicBool::new(false))?
                        .outcome?;
                }
                *best = best.min(started.elapsed().as_secs_f64());
            }
        }
        println!(
            "{path} ({end} s): {:.1} / {:.1} / {:.1} ms; a parameter costs {:.2} runs (two: {:.2} each)",
            times[0] * 1e3,
            times[1] * 1e3,
            times[2] * 1e3,
            (times[1] - times[0]) / times[0],
            (times[2] - times[0]) / (2.0 * times[0])
        );
    }
    Ok(())
}
