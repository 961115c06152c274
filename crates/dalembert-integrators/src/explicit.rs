//! Fixed-step explicit methods on the first-order form `y = [q; v]`, `ẏ = [T(q) v; v̇(t, q, v)]`
//! (`T(q) v` = [`dalembert_system::MultibodySystem::position_rates`], `v` itself when `v = q̇`).

use dalembert_system::{DynamicsError, Formulation, Stabilization};

/// Preallocated storage for the fixed-step methods.
pub(crate) struct FixedWork {
    n_q: usize,
    k: [Vec<f64>; 4],
    y_tmp: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
}

impl FixedWork {
    pub fn new(n_q: usize, n_v: usize, m: usize) -> Self {
        FixedWork {
            n_q,
            k: std::array::from_fn(|_| vec![0.0; n_q + n_v]),
            y_tmp: vec![0.0; n_q + n_v],
            qdd: vec![0.0; n_v],
            lambda: vec![0.0; m],
        }
    }
}

/// `out = [T(q) v; v̇]` at `(t, y = [q; v])`.
pub(crate) fn derivative<F: Formulation + ?Sized>(
    f: &mut F,
    t: f64,
    y: &[f64],
    stab: Stabilization,
    qdd: &mut [f64],
    lambda: &mut [f64],
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    let n_q = y.len() - qdd.len();
    let (q, qd) = y.split_at(n_q);
    f.accelerations(t, q, qd, stab, qdd, lambda)?;
    let (rates, vdot) = out.split_at_mut(n_q);
    f.system().position_rates(q, qd, rates);
    vdot.copy_from_slice(qdd);
    Ok(())
}

/// One semi-implicit Euler step: `v ← v + h v̇(t, q, v)`, then `q ← q ⊕ h v`
/// ([`dalembert_system::MultibodySystem::integrate_positions`], `q + h v` for planar bodies).
pub(crate) fn symplectic_euler_step<F: Formulation + ?Sized>(
    f: &mut F,
    w: &mut FixedWork,
    t: f64,
    h: f64,
    y: &mut [f64],
    stab: Stabilization,
) -> Result<(), DynamicsError> {
    let n_q = w.n_q;
    {
        let (q, qd) = y.split_at(n_q);
        f.accelerations(t, q, qd, stab, &mut w.qdd, &mut w.lambda)?;
    }
    let (q, qd) = y.split_at_mut(n_q);
    for (v, a) in qd.iter_mut().zip(&w.qdd) {
        *v += h * a;
    }
    // q ← q ⊕ h v (the system's position update; the driver restores its invariants).
    f.system().integrate_positions(q, qd, h);
    Ok(())
}

/// One classic Runge–Kutta step on `y = [q; v]` (the driver restores the position invariants after it).
pub(crate) fn rk4_step<F: Formulation + ?Sized>(
    f: &mut F,
    w: &mut FixedWork,
    t: f64,
    h: f64,
    y: &mut [f64],
    stab: Stabilization,
) -> Result<(), DynamicsError> {
    let FixedWork {
        k, y_tmp, qdd, lambda, ..
    } = w;
    let [k1, k2, k3, k4] = k;
    derivative(f, t, y, stab, qdd, lambda, k1)?;
    for i in 0..y.len() {
        y_tmp[i] = y[i] + 0.5 * h * k1[i];
    }
    derivative(f, t + 0.5 * h, y_tmp, stab, qdd, lambda, k2)?;
    for i in 0..y.len() {
        y_tmp[i] = y[i] + 0.5 * h * k2[i];
    }
    derivative(f, t + 0.5 * h, y_tmp, stab, qdd, lambda, k3)?;
    for i in 0..y.len() {
        y_tmp[i] = y[i] + h * k3[i];
    }
    derivative(f, t + h, y_tmp, stab, qdd, lambda, k4)?;
    for i in 0..y.len() {
        y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    Ok(())
}
