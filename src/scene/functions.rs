//! Time functions written in a scene: `{ kind = "...", ... }`, or `{ input = "NAME" }` for a named
//! input the run sets (held between sets, 0 before the first).
//!
//! For **drivers** a function describes the change from the value the driven quantity has in the
//! file, `f(t) = v₀ + g(t) − g(0)`, so the motion starts where the file puts it; `constant` holds an
//! absolute `value`; `absolute = true` uses `g(t)` as written. An input drives the change from the
//! file's value too (`v₀ + u`; `u` itself with `absolute = true`). For **forces** functions are
//! absolute.

use super::format::FunctionDef;
use dalembert_system::TimeFunction;
use std::cell::RefCell;

/// The index of input `name` in `inputs`, added when first met.
fn input_index(inputs: &RefCell<Vec<String>>, name: &str) -> usize {
    let mut names = inputs.borrow_mut();
    names.iter().position(|n| n == name).unwrap_or_else(|| {
        names.push(name.to_string());
        names.len() - 1
    })
}

/// The keys a function table sets besides `kind`, `input` and `absolute`.
fn shape_keys(def: &FunctionDef) -> Vec<&'static str> {
    let keys = [
        ("value", def.value.is_some()),
        ("initial", def.initial.is_some()),
        ("rate", def.rate.is_some()),
        ("amplitude", def.amplitude.is_some()),
        ("frequency", def.frequency.is_some()),
        ("phase", def.phase.is_some()),
        ("offset", def.offset.is_some()),
        ("coefficients", def.coefficients.is_some()),
        ("t0", def.t0.is_some()),
        ("t1", def.t1.is_some()),
        ("from", def.from.is_some()),
        ("to", def.to.is_some()),
    ];
    keys.into_iter().filter(|(_, set)| *set).map(|(k, _)| k).collect()
}

/// Converts a function table; `start` is `Some(v₀)` for drivers; input names are collected in
/// `inputs`. Errors name the missing or conflicting key.
pub(crate) fn time_function(
    def: &FunctionDef,
    start: Option<f64>,
    inputs: &RefCell<Vec<String>>,
) -> Result<TimeFunction, String> {
    let kind = match (&def.kind, &def.input) {
        (Some(_), Some(_)) => return Err("give 'kind' (a function of time) or 'input' (a named input), not both".into()),
        (None, Some(name)) => {
            if name.trim().is_empty() {
                return Err("'input' needs a name".into());
            }
            if let Some(key) = shape_keys(def).first() {
                return Err(format!("input '{name}': '{key}' belongs to a function of time, not to an input"));
            }
            let offset = if def.absolute.unwrap_or(false) { 0.0 } else { start.unwrap_or(0.0) };
            let gain = def.gain.unwrap_or(1.0);
            if !gain.is_finite() {
                return Err(format!("input '{name}': gain {gain} is not a finite value"));
            }
            let range = def.range.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
            if range[0].is_nan() || range[1].is_nan() || range[0] > range[1] {
                return Err(format!(
                    "input '{name}': range [{}, {}] is not an interval (lo ≤ hi)",
                    range[0], range[1]
                ));
            }
            return Ok(TimeFunction::Input {
                index: input_index(inputs, name),
                offset,
                gain,
                range,
            });
        }
        (None, None) => {
            return Err(
                "a function needs 'kind' (constant, linear, harmonic, polynomial or smooth-step) or 'input' (a named input)"
                    .into(),
            )
        }
        (Some(kind), None) => {
            if let Some(key) = [("gain", def.gain.is_some()), ("range", def.range.is_some())]
                .iter()
                .find_map(|(k, set)| set.then_some(*k))
            {
                return Err(format!("'{key}' belongs to an input ({{ input = \"NAME\", {key} = … }}), not to a function of time ({kind})"));
            }
            kind.as_str()
        }
    };
    let need = |v: Option<f64>, key: &str| v.ok_or_else(|| format!("function of kind '{kind}' needs '{key}'"));
    let g = match kind {
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
                "unknown function kind '{other}' (expected constant, linear, harmonic, polynomial or smooth-step; or give 'input' for a named input)"
            ))
        }
    };
    g.validate("function").map_err(|e| e.to_string())?;
    match (start, def.absolute.unwrap_or(false), kind) {
        // A smooth step already starts from the file's value (its `from`) unless `to` is relative.
        (Some(_), false, "smooth-step") | (None, _, _) | (_, true, _) => Ok(g),
        (Some(v0), false, _) => {
            let g0 = g.value(0.0);
            Ok(g.offset_by(v0 - g0))
        }
    }
}
