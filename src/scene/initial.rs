//! `[initial]`: where a scene starts when not from its file's configuration. Joint values and
//! rates (spatial scenes: [`crate::spatial::Model::move_joints`]), or positions and velocities by
//! their output columns (every scene; what `dalembert equilibrium --output` writes).

use crate::mechanism::Mechanism;
use crate::output::Rows;
use crate::scene::build::GIVEN_VELOCITY_WEIGHT;
use crate::scene::unknown_name;
use serde::Deserialize;
use std::collections::BTreeMap;

/// `[initial]` (`docs/scenes.md`, "Starting away from the file's configuration").
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct InitialDef {
    /// Joint values from the file's configuration (spatial scenes).
    #[serde(default)]
    pub joints: BTreeMap<String, f64>,
    /// Joint rates (spatial scenes).
    #[serde(default)]
    pub rates: BTreeMap<String, f64>,
    /// Positions by output column (`rod.x`, `top.e0`): the others stay the file's.
    #[serde(default)]
    pub positions: BTreeMap<String, f64>,
    /// Velocities by output column (`rod.vx`, `top.wx`, global as in the output): held in the
    /// velocity assembly; the others the least change.
    #[serde(default)]
    pub velocities: BTreeMap<String, f64>,
}

/// Sets the positions and velocities `initial` names in `(q, q̇)` and holds those velocities
/// (`weights`). A spatial body's Euler parameters are given all four or none (then normalized),
/// its angular velocity all three components or none (global, turned into the body's axes).
pub(crate) fn apply(
    model: &Mechanism,
    initial: &InitialDef,
    q: &mut [f64],
    qd: &mut [f64],
    weights: &mut [f64],
) -> Result<(), String> {
    if initial.positions.is_empty() && initial.velocities.is_empty() {
        return Ok(());
    }
    if !initial.joints.is_empty() || !initial.rates.is_empty() {
        return Err("[initial]: give joints and rates, or positions and velocities, not both".into());
    }
    let rows = Rows::new(model);
    let names = rows.names();
    let (q_columns, v_columns) = rows.state_columns(model);
    let index = |columns: &[usize], name: &str, what: &str| -> Result<usize, String> {
        columns.iter().position(|&k| names[k] == name).ok_or_else(|| {
            let known: Vec<&str> = columns.iter().map(|&k| names[k].as_str()).collect();
            format!("[initial]: {}", unknown_name(what, name, &known))
        })
    };
    for (name, &value) in &initial.positions {
        if !value.is_finite() {
            return Err(format!("[initial]: positions: {name} = {value} is not a finite value"));
        }
        q[index(&q_columns, name, "position column")?] = value;
    }
    let per_q = q.len() / model.num_bodies().max(1);
    if per_q == 7 {
        // Euler parameters: all four of a body or none, then unit length.
        for (b, chunk) in q.chunks_exact_mut(7).enumerate() {
            let given = (3..7)
                .filter(|&k| initial.positions.contains_key(&names[q_columns[7 * b + k]]))
                .count();
            if given != 0 && given != 4 {
                return Err(format!(
                    "[initial]: positions: give all four Euler parameters of body '{}' ({}), or none",
                    body_of(&names[q_columns[7 * b]]),
                    (3..7)
                        .map(|k| names[q_columns[7 * b + k]].as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ));
            }
            let norm = chunk[3..].iter().map(|x| x * x).sum::<f64>().sqrt();
            if given == 4 && !(norm > 0.5 && norm < 2.0) {
                return Err(format!(
                    "[initial]: positions: the Euler parameters of body '{}' have length {norm}, not 1",
                    body_of(&names[q_columns[7 * b]])
                ));
            }
            chunk[3..].iter_mut().for_each(|x| *x /= norm);
        }
    }
    for (name, &value) in &initial.velocities {
        if !value.is_finite() {
            return Err(format!("[initial]: velocities: {name} = {value} is not a finite value"));
        }
        let k = index(&v_columns, name, "velocity column")?;
        qd[k] = value;
        weights[k] = GIVEN_VELOCITY_WEIGHT;
    }
    if per_q == 7 {
        // Angular velocities: global in the output, the body's own axes in the model.
        for b in 0..model.num_bodies() {
            let w: Vec<&String> = (3..6).map(|k| &names[v_columns[6 * b + k]]).collect();
            let given = w.iter().filter(|n| initial.velocities.contains_key(n.as_str())).count();
            if given == 0 {
                continue;
            }
            if given != 3 {
                return Err(format!(
                    "[initial]: velocities: give all three of {} (global), or none",
                    w.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
                ));
            }
            let e = [q[7 * b + 3], q[7 * b + 4], q[7 * b + 5], q[7 * b + 6]];
            let global = nalgebra::Vector3::new(qd[6 * b + 3], qd[6 * b + 4], qd[6 * b + 5]);
            let own = dalembert_spatial::euler_parameters::rotation(&e).transpose() * global;
            qd[6 * b + 3..6 * b + 6].copy_from_slice(own.as_slice());
        }
    }
    Ok(())
}

/// The body of an output column (`crank` of `crank.x`).
fn body_of(column: &str) -> &str {
    column.rsplit_once('.').map_or(column, |(b, _)| b)
}
