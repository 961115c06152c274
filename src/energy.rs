//! The energy balance of a run (`docs/energy.md`): for a model that is not conservative, the
//! energy `E = T + V` changes by the work `W` of the applied forces without potential and of the
//! drivers, so `E − W` is what stays constant in the exact motion. A run's `E − W` drifts only by
//! its integration (and quadrature) error: the number that shows a non-conservative run is right.

use dalembert_integrators::Sample;
use dalembert_system::{MultibodySystem, PowerProbe};

/// `E(t) − W(t)` along a run, from its output samples: `W = ∫ P dt` with `P` the power of the
/// non-conservative applied forces ([`MultibodySystem::nonconservative_power`]) and of the
/// constraint forces `−λᵀ C_q v` (drivers; the joints' is zero on the constraints), less the
/// kinetic energy impacts at joint limits took (`docs/limits.md`). Where the run carries `W`
/// integrated along its steps ([`Sample::work`]: a model whose forces switch, such as contacts
/// and friction), that is taken; otherwise the integral is taken over each interval between
/// samples on the parabola through the last three samples (third order in the sample interval;
/// `docs/energy.md`, eq. E4).
#[derive(Debug, Clone)]
pub struct EnergyBalance {
    probe: PowerProbe,
    /// The last three `(t, P)`, oldest first.
    points: Vec<(f64, f64)>,
    /// Samples added.
    samples: u64,
    /// `W` up to the last sample.
    work: f64,
    /// The kinetic energy impacts took up to the last sample (`docs/limits.md`, (L4)).
    impacts: f64,
    /// `E − W` at the first sample.
    first: Option<f64>,
    /// The largest `|E − W − (E₀ − W₀)|` so far.
    largest_drift: f64,
    /// True once a sample carried the work along the run's steps.
    along_steps: bool,
}

impl EnergyBalance {
    /// An empty balance for runs of `system`.
    pub fn new(system: &dyn MultibodySystem) -> Self {
        EnergyBalance {
            probe: PowerProbe::new(system),
            points: Vec::with_capacity(3),
            samples: 0,
            work: 0.0,
            impacts: 0.0,
            first: None,
            largest_drift: 0.0,
            along_steps: false,
        }
    }

    /// The power `P` of the non-conservative forces and drivers at sample `s`.
    pub fn power(&mut self, system: &dyn MultibodySystem, s: &Sample<'_>) -> f64 {
        self.probe.power(system, (s.t, s.q, s.qd), s.lambda, s.friction)
    }

    /// Adds sample `s` (samples in increasing time) and returns `E − W` there.
    pub fn push(&mut self, system: &dyn MultibodySystem, s: &Sample<'_>) -> f64 {
        if s.work.is_finite() {
            // Integrated along the run's steps.
            self.samples += 1;
            self.work = s.work;
            self.along_steps = true;
            return self.balance(s);
        }
        let p = self.power(system, s);
        if self.points.len() == 3 {
            self.points.remove(0);
        }
        self.points.push((s.t, p));
        self.samples += 1;
        match *self.points.as_slice() {
            [(t0, p0), (t1, p1)] => self.work += 0.5 * (t1 - t0) * (p0 + p1),
            [(t0, p0), (t1, p1), (t2, p2)] => {
                let (h1, h2) = (t1 - t0, t2 - t1);
                if self.samples == 3 {
                    // The first interval again, on the parabola through the first three samples
                    // instead of the trapezoid.
                    self.work += parabola(h2, h1, p2, p1, p0) - 0.5 * h1 * (p0 + p1);
                }
                self.work += parabola(h1, h2, p0, p1, p2);
            }
            _ => {}
        }
        self.balance(s)
    }

    /// `E − W` at sample `s`, its work counted; the largest drift updated.
    fn balance(&mut self, s: &Sample<'_>) -> f64 {
        self.impacts = s.impact_loss;
        let balance = s.energy - self.work();
        let first = *self.first.get_or_insert(balance);
        self.largest_drift = self.largest_drift.max((balance - first).abs());
        balance
    }

    /// True when the work came integrated along the run's steps ([`Sample::work`]), false when
    /// it was integrated over the samples.
    pub fn along_steps(&self) -> bool {
        self.along_steps
    }

    /// `W`: the work of the non-conservative forces and drivers up to the last sample, less the
    /// kinetic energy impacts took (J).
    pub fn work(&self) -> f64 {
        self.work - self.impacts
    }

    /// The largest change of `E − W` from its first value (J).
    pub fn largest_drift(&self) -> f64 {
        self.largest_drift
    }
}

/// `∫` over the far interval (length `far`, from the middle node on) of the parabola through
/// values `p_near_end, p_mid, p_far_end` at `−near, 0, far` (`docs/energy.md`, eq. E4).
fn parabola(near: f64, far: f64, p_near: f64, p_mid: f64, p_far: f64) -> f64 {
    let (h1, h2) = (near, far);
    let w0 = -h2.powi(3) / (6.0 * h1 * (h1 + h2));
    let w1 = h2 * h2 / (6.0 * h1) + 0.5 * h2;
    let w2 = (h2 * h2 / 3.0 + 0.5 * h1 * h2) / (h1 + h2);
    w0 * p_near + w1 * p_mid + w2 * p_far
}
