//! The integration methods, one file (or folder) each: its [`Stepper`](crate::Stepper), its
//! [`MethodEntry`](crate::MethodEntry) and its typed [`Method`](crate::Method) constructor.

pub(crate) mod ali3p;
pub(crate) mod dopri5;
pub(crate) mod first_order;
pub(crate) mod generalized_alpha;
pub(crate) mod rk4;
pub(crate) mod symplectic_euler;

/// `out = now + ratio (now − before)`: the linear extrapolation of the last two steps' values to
/// the next step, `ratio` the next step over the last one (0 without history: the last values).
/// The implicit methods start Newton there (an O(h²) guess against O(h) for the last values).
pub(crate) fn extrapolate(out: &mut [f64], now: &[f64], before: &[f64], ratio: f64) {
    for (p, (n, b)) in out.iter_mut().zip(now.iter().zip(before)) {
        *p = n + ratio * (n - b);
    }
}

/// `h / h_prev`, or 0 when there is no previous step (`h_prev` NaN).
pub(crate) fn step_ratio(h: f64, h_prev: f64) -> f64 {
    if h_prev.is_nan() {
        0.0
    } else {
        h / h_prev
    }
}
