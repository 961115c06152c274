//! Time functions written in a scene: `{ kind = "...", ... }`.
//!
//! For **drivers** a function describes the change from the value the driven quantity has in the
//! file, `f(t) = v₀ + g(t) − g(0)`, so the motion starts where the file puts it; `constant` holds an
//! absolute `value`; `absolute = true` uses `g(t)` as written. For **forces** functions are absolute.

use super::format::FunctionDef;
use dalembert_kinematics::TimeFunction;

/// Converts a function table; `start` is `Some(v₀)` for drivers. Errors name the missing key.
pub(crate) fn time_function(def: &FunctionDef, start: Option<f64>) -> Result<TimeFunction, String> {
    let need = |v: Option<f64>, key: &str| v.ok_or_else(|| format!("function of kind '{}' needs '{key}'", def.kind));
    let g = match def.kind.as_str() {
        "constant" => return Ok(TimeFunction::Constant(need(def.value, "value")?)),
        "linear" => TimeFunction::Linear {
            initial: def.initial.unwrap_or(0.0),
            rate: need(def.rate, "rate")?,
        },
        "harmonic" => TimeFunction::Harmonic {
            offset: def.offset.unwrap_or(0.0),
            amplitude: need(def.amplitude, "amplitude")?,
            frequency: need(def.frequency, "frequency")?,
            phase: def.phase.unwrap_or(0.0),
        },
        "polynomial" => TimeFunction::Polynomial(
            def.coefficients
                .clone()
                .ok_or_else(|| "function of kind 'polynomial' needs 'coefficients'".to_string())?,
        ),
        "smooth-step" => TimeFunction::SmoothStep {
            t0: need(def.t0, "t0")?,
            t1: need(def.t1, "t1")?,
            from: def.from.or(start).unwrap_or(0.0),
            to: need(def.to, "to")?,
        },
        other => {
            return Err(format!(
                "unknown function kind '{other}' (expected constant, linear, harmonic, polynomial or smooth-step)"
            ))
        }
    };
    g.validate("function").map_err(|e| e.to_string())?;
    match (start, def.absolute.unwrap_or(false), def.kind.as_str()) {
        // A smooth step already starts from the file's value (its `from`) unless `to` is relative.
        (Some(_), false, "smooth-step") | (None, _, _) | (_, true, _) => Ok(g),
        (Some(v0), false, _) => {
            let g0 = g.value(0.0);
            Ok(g.offset_by(v0 - g0))
        }
    }
}
