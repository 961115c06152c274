//! The first-order form the explicit methods integrate: `y = [q; v]`,
//! `ẏ = [T(q) v; v̇(t, q, v)]` (`T(q) v` = [`dalembert_system::MultibodySystem::position_rates`],
//! `v` itself when `v = q̇`).

use dalembert_system::{Baumgarte, DynamicsError, Formulation};

/// `out = [T(q) v; v̇]` at `(t, y = [q; v])`; `qdd` and `lambda` are the formulation's outputs.
pub(crate) fn derivative(
    f: &mut dyn Formulation,
    t: f64,
    y: &[f64],
    baumgarte: Option<Baumgarte>,
    qdd: &mut [f64],
    lambda: &mut [f64],
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    let n_q = y.len() - qdd.len();
    let (q, qd) = y.split_at(n_q);
    f.accelerations(t, q, qd, baumgarte, qdd, lambda)?;
    let (rates, vdot) = out.split_at_mut(n_q);
    f.system().position_rates(q, qd, rates);
    vdot.copy_from_slice(qdd);
    Ok(())
}
