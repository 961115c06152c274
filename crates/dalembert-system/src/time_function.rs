//! Scalar functions of time with exact first and second derivatives, for drivers and forces.

use std::fmt;
use std::sync::Arc;

/// A user-supplied time function returning `[f(t), f'(t), f''(t)]`.
pub type TimeClosure = Arc<dyn Fn(f64) -> [f64; 3] + Send + Sync>;

/// A function of time `f(t)` with exact derivatives `f'(t)`, `f''(t)`.
#[derive(Clone)]
pub enum TimeFunction {
    /// `f(t) = value`.
    Constant(f64),
    /// `f(t) = initial + rate · t`.
    Linear {
        /// Value at `t = 0`.
        initial: f64,
        /// Slope.
        rate: f64,
    },
    /// `f(t) = Σ c_k t^k` (coefficients in increasing powers).
    Polynomial(Vec<f64>),
    /// `f(t) = offset + amplitude · sin(2π · frequency · t + phase)`.
    Harmonic {
        /// Mean value.
        offset: f64,
        /// Amplitude.
        amplitude: f64,
        /// Frequency in Hz.
        frequency: f64,
        /// Phase in rad.
        phase: f64,
    },
    /// A quintic smooth step from `from` at `t0` to `to` at `t1`: constant outside, and `f`, `f'`,
    /// `f''` continuous everywhere (`s = (t−t0)/(t1−t0)`, `f = from + (to−from)(10s³ − 15s⁴ + 6s⁵)`).
    SmoothStep {
        /// Start time.
        t0: f64,
        /// End time (must exceed `t0`).
        t1: f64,
        /// Value before `t0`.
        from: f64,
        /// Value after `t1`.
        to: f64,
    },
    /// A user closure returning `[f, f', f'']`; its derivatives are the user's responsibility.
    Custom(TimeClosure),
    /// Named input `index` of the model times `gain` plus `offset`: `f(t) = offset + gain u`,
    /// where `u` is the value the run last set (held between sets, 0 before the first;
    /// [`crate::inputs`]). Its derivatives are zero: a change of the value is a step, and an
    /// implicit method's tangent holds it constant over a step.
    Input {
        /// The input's index in the model's list of inputs.
        index: usize,
        /// Added to the input's value (a driver's value in the file).
        offset: f64,
        /// Multiplies the input's value (an MJCF motor's `gear`; 1 by default).
        gain: f64,
        /// The input's value is held within `[lo, hi]` before the gain (an MJCF motor's
        /// `ctrlrange` and `forcerange`; unbounded by default).
        range: [f64; 2],
    },
}

impl fmt::Debug for TimeFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TimeFunction::Constant(v) => write!(f, "Constant({v})"),
            TimeFunction::Linear { initial, rate } => write!(f, "Linear({initial} + {rate} t)"),
            TimeFunction::Polynomial(c) => write!(f, "Polynomial({c:?})"),
            TimeFunction::Harmonic {
                offset,
                amplitude,
                frequency,
                phase,
            } => {
                write!(f, "Harmonic({offset} + {amplitude} sin(2π {frequency} t + {phase}))")
            }
            TimeFunction::SmoothStep { t0, t1, from, to } => {
                write!(f, "SmoothStep({from} at {t0} → {to} at {t1})")
            }
            TimeFunction::Custom(_) => write!(f, "Custom(..)"),
            TimeFunction::Input {
                index,
                offset,
                gain,
                range: [lo, hi],
            } => write!(f, "{gain} clamp(Input({index}), {lo}, {hi}) + {offset}"),
        }
    }
}

impl TimeFunction {
    /// Wraps a closure returning `[f, f', f'']`.
    pub fn custom(f: impl Fn(f64) -> [f64; 3] + Send + Sync + 'static) -> Self {
        TimeFunction::Custom(Arc::new(f))
    }

    /// `f(t)`.
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        self.eval(t)[0]
    }

    /// `[f(t), f'(t), f''(t)]`.
    pub fn eval(&self, t: f64) -> [f64; 3] {
        match self {
            TimeFunction::Constant(v) => [*v, 0.0, 0.0],
            TimeFunction::Linear { initial, rate } => [initial + rate * t, *rate, 0.0],
            TimeFunction::Polynomial(c) => {
                // Horner for f, f', f'' together.
                let (mut f, mut d1, mut d2) = (0.0, 0.0, 0.0);
                for &ck in c.iter().rev() {
                    d2 = d2 * t + 2.0 * d1;
                    d1 = d1 * t + f;
                    f = f * t + ck;
                }
                [f, d1, d2]
            }
            TimeFunction::Harmonic {
                offset,
                amplitude,
                frequency,
                phase,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                let (s, c) = (w * t + phase).sin_cos();
                [offset + amplitude * s, amplitude * w * c, -amplitude * w * w * s]
            }
            TimeFunction::SmoothStep { t0, t1, from, to } => {
                let d = t1 - t0;
                if t <= *t0 {
                    return [*from, 0.0, 0.0];
                }
                if t >= *t1 {
                    return [*to, 0.0, 0.0];
                }
                let s = (t - t0) / d;
                let h = to - from;
                let s2 = s * s;
                let p = s2 * s * (10.0 - 15.0 * s + 6.0 * s2);
                let dp = 30.0 * s2 * (1.0 - 2.0 * s + s2);
                let ddp = 60.0 * s * (1.0 - 3.0 * s + 2.0 * s2);
                [from + h * p, h * dp / d, h * ddp / (d * d)]
            }
            TimeFunction::Custom(f) => f(t),
            TimeFunction::Input {
                index,
                offset,
                gain,
                range: [lo, hi],
            } => [
                offset + gain * crate::inputs::input_value(*index).clamp(*lo, *hi),
                0.0,
                0.0,
            ],
        }
    }

    /// The same function shifted by a constant: `f(t) + c`.
    pub fn offset_by(self, c: f64) -> TimeFunction {
        match self {
            TimeFunction::Constant(v) => TimeFunction::Constant(v + c),
            TimeFunction::Linear { initial, rate } => TimeFunction::Linear {
                initial: initial + c,
                rate,
            },
            TimeFunction::Polynomial(mut k) => {
                if k.is_empty() {
                    k.push(0.0);
                }
                k[0] += c;
                TimeFunction::Polynomial(k)
            }
            TimeFunction::Harmonic {
                offset,
                amplitude,
                frequency,
                phase,
            } => TimeFunction::Harmonic {
                offset: offset + c,
                amplitude,
                frequency,
                phase,
            },
            TimeFunction::SmoothStep { t0, t1, from, to } => TimeFunction::SmoothStep {
                t0,
                t1,
                from: from + c,
                to: to + c,
            },
            TimeFunction::Input {
                index,
                offset,
                gain,
                range,
            } => TimeFunction::Input {
                index,
                offset: offset + c,
                gain,
                range,
            },
            TimeFunction::Custom(f) => TimeFunction::custom(move |t| {
                let [v, d1, d2] = f(t);
                [v + c, d1, d2]
            }),
        }
    }

    /// Checks the parameters are finite (and `t1 > t0` for a smooth step); `what` names the owner.
    pub fn validate(&self, what: &str) -> Result<(), crate::ModelError> {
        let bad = |msg: &str| {
            Err(crate::ModelError::InvalidParameter {
                element: what.to_string(),
                what: msg.to_string(),
            })
        };
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        match self {
            TimeFunction::Constant(v) if !v.is_finite() => bad("constant value must be finite"),
            TimeFunction::Input { offset, gain, .. } if !offset.is_finite() || !gain.is_finite() => {
                bad("an input's offset and gain must be finite")
            }
            TimeFunction::Input { range: [lo, hi], .. } if lo.is_nan() || hi.is_nan() || lo > hi => {
                bad("an input's range must be [lo, hi] with lo ≤ hi")
            }
            TimeFunction::Linear { initial, rate } if !finite(&[*initial, *rate]) => {
                bad("linear function parameters must be finite")
            }
            TimeFunction::Polynomial(c) if !finite(c) => bad("polynomial coefficients must be finite"),
            TimeFunction::Harmonic {
                offset,
                amplitude,
                frequency,
                phase,
            } if !finite(&[*offset, *amplitude, *frequency, *phase]) => bad("harmonic parameters must be finite"),
            TimeFunction::SmoothStep { t0, t1, from, to } => {
                if !finite(&[*t0, *t1, *from, *to]) {
                    bad("smooth-step parameters must be finite")
                } else if t1 <= t0 {
                    bad("smooth step needs t1 > t0")
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Derivatives of every built-in kind against central differences (h = 1e-4: truncation
    /// O(h²)·f''' ≲ 1e-6 for these smooth functions, round-off ≲ 1e-16/h² = 1e-8).
    #[test]
    fn derivatives_match_finite_differences() {
        let fs = [
            TimeFunction::Constant(2.0),
            TimeFunction::Linear {
                initial: 0.5,
                rate: 6.5,
            },
            TimeFunction::Polynomial(vec![1.0, -2.0, 0.5, 0.25]),
            TimeFunction::Harmonic {
                offset: 0.1,
                amplitude: 0.3,
                frequency: 1.5,
                phase: 0.4,
            },
            TimeFunction::SmoothStep {
                t0: 0.2,
                t1: 1.2,
                from: -1.0,
                to: 2.0,
            },
        ];
        let h = 1e-4;
        for f in &fs {
            for &t in &[0.0, 0.35, 0.7, 1.1, 1.5] {
                let [_, d1, d2] = f.eval(t);
                let fd1 = (f.value(t + h) - f.value(t - h)) / (2.0 * h);
                let fd2 = (f.value(t + h) - 2.0 * f.value(t) + f.value(t - h)) / (h * h);
                assert!((fd1 - d1).abs() < 1e-6, "{f:?} f' at {t}: {fd1} vs {d1}");
                assert!((fd2 - d2).abs() < 1e-4, "{f:?} f'' at {t}: {fd2} vs {d2}");
            }
        }
    }

    #[test]
    fn smooth_step_endpoints() {
        let f = TimeFunction::SmoothStep {
            t0: 1.0,
            t1: 3.0,
            from: 2.0,
            to: 5.0,
        };
        assert_eq!(f.eval(0.5), [2.0, 0.0, 0.0]);
        assert_eq!(f.eval(4.0), [5.0, 0.0, 0.0]);
        // Midpoint of the quintic is exactly half way with zero curvature.
        let [v, _, a] = f.eval(2.0);
        assert!((v - 3.5).abs() < 1e-15 && a.abs() < 1e-12);
    }

    #[test]
    fn offset_keeps_derivatives() {
        let f = TimeFunction::Harmonic {
            offset: 0.0,
            amplitude: 1.0,
            frequency: 1.0,
            phase: 0.0,
        };
        let g = f.clone().offset_by(2.0);
        let (a, b) = (f.eval(0.3), g.eval(0.3));
        assert!((b[0] - a[0] - 2.0).abs() < 1e-15 && a[1] == b[1] && a[2] == b[2]);
    }
}
