//! Second-order forward-mode differentiation in one variable: `Jet { v, d, dd }` carries
//! `f(φ)`, `f'(φ)`, `f''(φ)` through arithmetic and elementary functions. Used to derive minimal-
//! coordinate equations of motion from closed-form kinematics, independently of the constraint code.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A value with its first and second derivative with respect to one variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jet {
    /// Value.
    pub v: f64,
    /// First derivative.
    pub d: f64,
    /// Second derivative.
    pub dd: f64,
}

impl Jet {
    /// The independent variable at `x`.
    pub fn var(x: f64) -> Jet {
        Jet { v: x, d: 1.0, dd: 0.0 }
    }
    /// A constant.
    pub fn c(x: f64) -> Jet {
        Jet { v: x, d: 0.0, dd: 0.0 }
    }
    /// Applies `g` with derivatives `g0, g1, g2` at `self.v` (chain rule to second order).
    fn chain(self, g0: f64, g1: f64, g2: f64) -> Jet {
        Jet {
            v: g0,
            d: g1 * self.d,
            dd: g2 * self.d * self.d + g1 * self.dd,
        }
    }
    /// sin.
    pub fn sin(self) -> Jet {
        let (s, c) = self.v.sin_cos();
        self.chain(s, c, -s)
    }
    /// cos.
    pub fn cos(self) -> Jet {
        let (s, c) = self.v.sin_cos();
        self.chain(c, -s, -c)
    }
    /// sqrt.
    pub fn sqrt(self) -> Jet {
        let r = self.v.sqrt();
        self.chain(r, 0.5 / r, -0.25 / (r * self.v))
    }
    /// atan2(self, x).
    pub fn atan2(self, x: Jet) -> Jet {
        // θ = atan2(y, x): θ' = (x y' − y x') / r², differentiate once more by the quotient rule.
        let y = self;
        let r2 = x * x + y * y;
        let num = x * Jet {
            v: y.d,
            d: y.dd,
            dd: 0.0,
        } - y * Jet {
            v: x.d,
            d: x.dd,
            dd: 0.0,
        };
        let q = num / r2;
        Jet {
            v: y.v.atan2(x.v),
            d: q.v,
            dd: q.d,
        }
    }
}

impl Add for Jet {
    type Output = Jet;
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            d: self.d + o.d,
            dd: self.dd + o.dd,
        }
    }
}
impl Sub for Jet {
    type Output = Jet;
    fn sub(self, o: Jet) -> Jet {
        Jet {
            v: self.v - o.v,
            d: self.d - o.d,
            dd: self.dd - o.dd,
        }
    }
}
impl Neg for Jet {
    type Output = Jet;
    fn neg(self) -> Jet {
        Jet {
            v: -self.v,
            d: -self.d,
            dd: -self.dd,
        }
    }
}
impl Mul for Jet {
    type Output = Jet;
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            d: self.d * o.v + self.v * o.d,
            dd: self.dd * o.v + 2.0 * self.d * o.d + self.v * o.dd,
        }
    }
}
impl Div for Jet {
    type Output = Jet;
    #[allow(clippy::suspicious_arithmetic_impl)] // a / b = a · (1/b), exact for jets
    fn div(self, o: Jet) -> Jet {
        self * o.recip()
    }
}
impl Mul<f64> for Jet {
    type Output = Jet;
    fn mul(self, k: f64) -> Jet {
        Jet {
            v: self.v * k,
            d: self.d * k,
            dd: self.dd * k,
        }
    }
}

impl Jet {
    /// 1 / self.
    pub fn recip(self) -> Jet {
        let x = self.v;
        self.chain(1.0 / x, -1.0 / (x * x), 2.0 / (x * x * x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_of_a_composite_match_hand_values() {
        // f = atan2(sin φ, 2 + cos φ) / sqrt(1 + φ²) at φ = 0.7, against central differences.
        let f = |p: Jet| (p.sin().atan2(Jet::c(2.0) + p.cos())) / (Jet::c(1.0) + p * p).sqrt();
        let x = 0.7;
        let j = f(Jet::var(x));
        let g = |x: f64| f(Jet::c(x)).v;
        let h = 1e-4;
        let d1 = (g(x + h) - g(x - h)) / (2.0 * h);
        let d2 = (g(x + h) - 2.0 * g(x) + g(x - h)) / (h * h);
        assert!((j.d - d1).abs() < 1e-8, "{} {}", j.d, d1);
        assert!((j.dd - d2).abs() < 1e-6, "{} {}", j.dd, d2);
    }
}
