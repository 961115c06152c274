//! The work `W` of a model's non-conservative forces, drivers and joint friction, integrated
//! along the run's own steps (`docs/energy.md`, "Along the steps"), for the energy balance
//! `E − W` of a model whose forces switch (contacts, stick and slip, limits): on output samples
//! coarser than the steps, a contact that begins and ends between two samples is missed. Built
//! with the run; nothing is allocated after.

use dalembert_system::{Baumgarte, DynamicsError, Formulation, PowerProbe};

/// `W` along the steps: the power `P` at each step's end, integrated over each step on the cubic
/// through the last four step ends (fourth order in the step; fewer points, and lower order, on
/// the first steps after a restart or an event, which are taken again as points come).
pub(super) struct WorkAlongSteps {
    probe: PowerProbe,
    /// True when `P` needs the multipliers or the friction forces (an evaluation at the step's
    /// end); otherwise it is a function of the state alone.
    evaluates: bool,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    /// The last four `(t, P)` at step ends (oldest first), `len` of them.
    points: [(f64, f64); 4],
    len: usize,
    /// True while the points all follow the last restart (or event): `W` is then `base` plus
    /// the integral from the first point on the polynomial through all of them.
    fresh: bool,
    base: f64,
    /// `W` at the last point and at the one before it.
    work: f64,
    work_before: f64,
    /// True when the last step ended at an event.
    after_event: bool,
}

impl WorkAlongSteps {
    /// The tracker for a run of `f` from `(t, y = [q; v])` (`n_q` positions), or `None` where
    /// the output samples suffice: a conservative model (`W = 0`), or one whose forces are
    /// smooth in time (no events, friction or limits).
    pub fn new(
        f: &mut dyn Formulation,
        (t, y, n_q): (f64, &[f64], usize),
        baumgarte: Option<Baumgarte>,
    ) -> Result<Option<Self>, DynamicsError> {
        let s = f.system();
        let switches = s.num_events() > 0 || !s.frictions().is_empty() || !s.limits().is_empty();
        if s.is_conservative() || !switches {
            return Ok(None);
        }
        let mut w = WorkAlongSteps {
            probe: PowerProbe::new(s),
            evaluates: !s.frictions().is_empty() || s.is_driven(),
            qdd: vec![0.0; s.layout().n_v()],
            lambda: vec![0.0; s.num_equations()],
            points: [(t, 0.0); 4],
            len: 0,
            fresh: true,
            base: 0.0,
            work: 0.0,
            work_before: 0.0,
            after_event: false,
        };
        w.restart(f, (t, y, n_q), baumgarte)?;
        Ok(Some(w))
    }

    /// `P` at `(t, y)`.
    fn power(
        &mut self,
        f: &mut dyn Formulation,
        (t, y, n_q): (f64, &[f64], usize),
        baumgarte: Option<Baumgarte>,
    ) -> Result<f64, DynamicsError> {
        let (q, v) = y.split_at(n_q);
        if !self.evaluates {
            return Ok(self.probe.power(f.system(), (t, q, v), &[], &[]));
        }
        f.accelerations(t, q, v, baumgarte, &mut self.qdd, &mut self.lambda)?;
        // The friction forces of the evaluation just made.
        Ok(self
            .probe
            .power(f.system(), (t, q, v), &self.lambda, f.friction_forces()))
    }

    /// The run starts again from `(t, y)` (its start, an event settled by an impulse, a state
    /// set, a time inside the last step made the run's own): `W` goes on from its value at `t`,
    /// the quadrature from this point (the power may jump there).
    pub fn restart(
        &mut self,
        f: &mut dyn Formulation,
        at: (f64, &[f64], usize),
        baumgarte: Option<Baumgarte>,
    ) -> Result<(), DynamicsError> {
        let p = self.power(f, at, baumgarte)?;
        self.work = self.at(at.0);
        self.begin((at.0, p));
        Ok(())
    }

    /// The quadrature starts at `point`, with `W` there.
    fn begin(&mut self, point: (f64, f64)) {
        self.points[0] = point;
        self.len = 1;
        self.fresh = true;
        self.base = self.work;
        self.work_before = self.work;
        self.after_event = false;
    }

    /// The run was moved to `t` (a state set, or the state shown inside the last step made the
    /// run's own): `W` is kept at its value there, and the quadrature waits for
    /// [`WorkAlongSteps::restart`] at the new state.
    pub fn move_to(&mut self, t: f64) {
        self.work = self.at(t);
        self.len = 0;
    }

    /// True after [`WorkAlongSteps::move_to`], until the restart.
    pub fn moved(&self) -> bool {
        self.len == 0
    }

    /// A step ended at `(t, y)`; `at_event` when it ended at an event, where the power's law
    /// changes (a contact begins or ends, a joint sticks): the quadrature of the steps after it
    /// starts from there.
    pub fn step(
        &mut self,
        f: &mut dyn Formulation,
        at: (f64, &[f64], usize),
        baumgarte: Option<Baumgarte>,
        at_event: bool,
    ) -> Result<(), DynamicsError> {
        let p = self.power(f, at, baumgarte)?;
        if self.after_event {
            self.begin(self.points[self.len - 1]);
        }
        if self.len == self.points.len() {
            self.points.rotate_left(1);
            self.len -= 1;
            self.fresh = false;
        }
        self.points[self.len] = (at.0, p);
        self.len += 1;
        let (first, middle, last) = (self.points[0].0, self.points[self.len - 2].0, at.0);
        if self.fresh {
            self.work_before = self.base + self.integral(first, middle);
            self.work = self.base + self.integral(first, last);
        } else {
            self.work_before = self.work;
            self.work += self.integral(middle, last);
        }
        // Kept until the next step: the samples inside this one are shown after it.
        self.after_event = at_event;
        Ok(())
    }

    /// `W` at `t`, in the last step (at its end, or before it on the same polynomial; at the
    /// last point where there is no step yet).
    pub fn at(&self, t: f64) -> f64 {
        if self.len < 2 || t >= self.points[self.len - 1].0 {
            return self.work;
        }
        let start = self.points[self.len - 2].0;
        self.work_before + self.integral(start, t.max(start))
    }

    /// `∫_a^b P dt` on the polynomial through the points (`docs/energy.md`, eq. E5), in the
    /// variable `u = (t − t_m) / s` from the last step's start `t_m` over its length `s`.
    fn integral(&self, a: f64, b: f64) -> f64 {
        let k = self.len;
        let tm = self.points[k - 2].0;
        let s = self.points[k - 1].0 - tm;
        if s.is_nan() || s <= 0.0 || b <= a {
            return 0.0;
        }
        // The monomial coefficients in u: the Vandermonde system, by elimination with pivoting.
        let mut m = [[0.0f64; 5]; 4];
        for (row, &(t, p)) in m.iter_mut().zip(&self.points[..k]) {
            let u = (t - tm) / s;
            let mut power = 1.0;
            for c in row.iter_mut().take(k) {
                *c = power;
                power *= u;
            }
            row[4] = p;
        }
        for col in 0..k {
            let pivot = (col..k)
                .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
                .unwrap_or(col);
            m.swap(col, pivot);
            let d = m[col][col];
            if d == 0.0 {
                return 0.0;
            }
            for i in 0..k {
                if i != col {
                    let factor = m[i][col] / d;
                    for j in col..5 {
                        m[i][j] -= factor * m[col][j];
                    }
                }
            }
        }
        let (ua, ub) = ((a - tm) / s, (b - tm) / s);
        let mut sum = 0.0;
        for (j, row) in m.iter().enumerate().take(k) {
            let e = (j + 1) as i32;
            sum += row[4] / row[j] * (ub.powi(e) - ua.powi(e)) / e as f64;
        }
        s * sum
    }
}
