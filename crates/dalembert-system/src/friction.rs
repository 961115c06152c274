//! Coulomb friction in joints, loaded by the joint's own reaction (`docs/friction.md`): what a
//! system says about each friction element ([`JointFriction`], [`SlipRow`]) and the exact
//! stick–slip law that turns the frictionless accelerations into the frictional ones
//! ([`solve_friction`]).
//!
//! For friction element `k` with slip rate `w_k = g_k·v` (the joint's relative speed or angular
//! velocity), slip acceleration `ẇ_k = g_k·v̇ + b_k`, normal load `N_k = |L_k λ|` (the norm of
//! some of the joint's multipliers) and friction force `F_k` (generalized force `g_kᵀ F_k`,
//! power `F_k w_k`):
//!
//! ```text
//! slipping in direction σ:  F_k = −c_k w_k − σ μ_k N_k(F)                                  (F1)
//! sticking:                 F_k = F_hold, the force that makes ẇ_k = 0, if |F_hold| ≤ μ_k N_k(F)   (F2)
//!                           otherwise F_k = sign(F_hold) μ_k N_k(F) − c_k w_k  (slip begins)   (F3)
//! ```
//!
//! Each element is in one [`Mode`] for a whole step, so that the step's stages see one smooth law;
//! the mode changes only at an event, at the end of a step shortened to end there: a slip whose
//! rate reaches zero sticks (if (F2) can hold it) or reverses, and a stuck joint whose rate
//! leaves its stick speed `w_s` slips ([`Mode::event`]). (F3) is continuous with (F1), so a
//! joint begins to slip within a step without a jump in its force.
//!
//! Accelerations and multipliers are affine in the friction forces: `v̇ = v̇₀ + Σ A_k F_k`,
//! `λ = λ₀ + Σ Λ_k F_k`, with `A_k`, `Λ_k` the response of the formulation to a unit generalized
//! force `g_k` (same state, same matrix). So stick is exact: the slip acceleration is zero to
//! round-off and a joint at rest stays at rest. (F1)–(F3) are solved joint by joint
//! (Gauss–Seidel sweeps); each joint's equation `F = b − σ μ |ℓ₀ + ℓ₁ F|` by Newton. It has one
//! solution when `μ |ℓ₁| < 1`; otherwise the friction force is not determined by the law (a
//! Painlevé configuration), reported as an error naming the joint.

use crate::{DynamicsError, MultibodySystem};

/// The most coordinates a slip row touches (two spatial bodies of six velocities each).
pub const SLIP_ROW_CAPACITY: usize = 12;

/// One friction element of a system, as the system describes it once.
#[derive(Debug, Clone, PartialEq)]
pub struct JointFriction {
    /// The joint's name (in errors and outputs).
    pub name: String,
    /// `μ_k`: the friction force per unit of `|L_k λ|` (the Coulomb coefficient for a slider, the
    /// coefficient times the pin radius for a revolute joint, in metres).
    pub coefficient: f64,
    /// `c_k`: viscous friction per unit slip rate (N·s/m or N·m·s/rad).
    pub viscous: f64,
    /// The multiplier rows whose Euclidean norm is the joint's normal load `N_k`.
    pub load_rows: Vec<usize>,
    /// `w_s`: the slip rate below which the joint counts as at rest (m/s or rad/s).
    pub stick_speed: f64,
}

/// The slip row of one friction element at a state: `w = Σ g_i v_i` and the bias `b` of
/// `ẇ = Σ g_i v̇_i + b`. Fixed capacity: filling it allocates nothing.
#[derive(Debug, Clone, Copy)]
pub struct SlipRow {
    entries: [(usize, f64); SLIP_ROW_CAPACITY],
    len: usize,
    /// `b`: the part of the slip acceleration that the accelerations do not give.
    pub bias: f64,
}

impl Default for SlipRow {
    fn default() -> Self {
        SlipRow {
            entries: [(0, 0.0); SLIP_ROW_CAPACITY],
            len: 0,
            bias: 0.0,
        }
    }
}

impl SlipRow {
    /// Empties the row.
    pub fn clear(&mut self) {
        self.len = 0;
        self.bias = 0.0;
    }

    /// Adds `value` at velocity coordinate `index` (ignored past the capacity, which no joint of
    /// two bodies reaches).
    pub fn push(&mut self, index: usize, value: f64) {
        if self.len < SLIP_ROW_CAPACITY {
            self.entries[self.len] = (index, value);
            self.len += 1;
        }
    }

    /// The entries `(velocity coordinate, g_i)`.
    pub fn entries(&self) -> &[(usize, f64)] {
        &self.entries[..self.len]
    }

    /// `g·x`.
    pub fn dot(&self, x: &[f64]) -> f64 {
        self.entries().iter().map(|&(i, g)| g * x[i]).sum()
    }

    /// Writes `g` as a dense vector (zeros elsewhere).
    pub fn write_dense(&self, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for &(i, g) in self.entries() {
            out[i] += g;
        }
    }
}

/// What a friction element does over a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// At rest (its slip rate within the stick speed): (F2), or (F3) where (F2) cannot hold it.
    Stick,
    /// Slipping in the direction of the sign (±1): (F1).
    Slip(f64),
}

impl Mode {
    /// The mode of an element whose slip rate is `w` at the start of a run.
    pub fn at(w: f64, stick_speed: f64) -> Mode {
        if w.abs() <= stick_speed {
            Mode::Stick
        } else {
            Mode::Slip(w.signum())
        }
    }

    /// The event function of the mode at slip rate `w`: positive while the mode holds, so that a
    /// sign change ends it: `σ w + w_s` for a slip (its rate passes zero by the stick speed, so
    /// that a slip that begins at rest starts clear of its event), `w_s − |w|` for a stuck joint
    /// (its rate leaves the stick speed).
    pub fn event(self, w: f64, stick_speed: f64) -> f64 {
        match self {
            Mode::Stick => stick_speed - w.abs(),
            Mode::Slip(sign) => sign * w + stick_speed,
        }
    }
}

/// One friction element's terms at a state, as [`solve_friction`] takes them.
#[derive(Debug, Clone)]
pub struct FrictionTerms {
    /// The slip row.
    pub row: SlipRow,
    /// `A_k`: `v̇` per unit friction force.
    pub dv: Vec<f64>,
    /// `Λ_k`: `λ` per unit friction force.
    pub dlambda: Vec<f64>,
    /// The friction force found (`F_k`).
    pub force: f64,
    /// True when the joint sticks ((F2) held it).
    pub sticks: bool,
    /// The element's mode over the step in progress.
    pub mode: Mode,
}

impl FrictionTerms {
    /// Storage for a system of `n` velocities and `m` multipliers.
    pub fn new(n: usize, m: usize) -> Self {
        FrictionTerms {
            row: SlipRow::default(),
            dv: vec![0.0; n],
            dlambda: vec![0.0; m],
            force: 0.0,
            sticks: false,
            mode: Mode::Stick,
        }
    }
}

/// The largest number of Gauss–Seidel sweeps over the friction elements.
const MAX_SWEEPS: usize = 200;

/// The largest number of Newton iterations of one element's equation.
const MAX_NEWTON: usize = 50;

/// Solves (F1)–(F3) for every element in its mode: on entry `a`, `lambda` are the frictionless
/// `v̇₀`, `λ₀` and `terms[k]` hold the rows, responses and modes; on exit `a`, `lambda` include the friction forces,
/// and `terms[k].force`, `terms[k].sticks` say what each element does. Allocates nothing.
pub fn solve_friction(
    system: &dyn MultibodySystem,
    t: f64,
    v: &[f64],
    a: &mut [f64],
    lambda: &mut [f64],
    terms: &mut [FrictionTerms],
) -> Result<(), DynamicsError> {
    let frictions = system.frictions();
    terms.iter_mut().for_each(|k| k.force = 0.0);
    for sweep in 0..MAX_SWEEPS {
        let mut change = 0.0f64;
        let mut scale = 0.0f64;
        for (spec, k) in frictions.iter().zip(terms.iter_mut()) {
            let old = k.force;
            let d = k.row.dot(&k.dv);
            if !(d > 0.0 && d.is_finite()) {
                return Err(DynamicsError::Friction {
                    time: t,
                    joint: spec.name.clone(),
                    what: format!("a friction force does not move the joint (its response is {d:e})"),
                });
            }
            // The load without this element's own force, and its change per unit force.
            let mut l0 = [0.0; 3];
            let mut l1 = [0.0; 3];
            for (j, &r) in spec.load_rows.iter().take(3).enumerate() {
                l0[j] = lambda[r] - k.dlambda[r] * old;
                l1[j] = k.dlambda[r];
            }
            let slope = spec.coefficient * l1.iter().map(|x| x * x).sum::<f64>().sqrt();
            if slope >= 1.0 {
                return Err(DynamicsError::Friction {
                    time: t,
                    joint: spec.name.clone(),
                    what: format!(
                        "the friction force is not determined by Coulomb's law (Painlevé): μ × the load's change \
                         per unit friction force is {slope:.3} ≥ 1"
                    ),
                });
            }
            let load = |f: f64| -> f64 {
                spec.coefficient
                    * (0..3)
                        .map(|j| (l0[j] + l1[j] * f).powi(2))
                        .sum::<f64>()
                        .sqrt()
            };
            let w = k.row.dot(v);
            let alpha0 = k.row.dot(a) + k.row.bias - d * old;
            let (base, sign, sticks) = match k.mode {
                Mode::Slip(sign) => (-spec.viscous * w, sign, false),
                Mode::Stick => {
                    let hold = -alpha0 / d;
                    if hold.abs() <= load(hold) {
                        (hold, 0.0, true)
                    } else {
                        (-spec.viscous * w, -hold.signum(), false)
                    }
                }
            };
            let force = if sign == 0.0 {
                base
            } else {
                newton(base, sign, &l0, &l1, spec.coefficient)
            };
            if !force.is_finite() {
                return Err(DynamicsError::Friction {
                    time: t,
                    joint: spec.name.clone(),
                    what: "the friction force is not finite".to_string(),
                });
            }
            k.force = force;
            k.sticks = sticks;
            let delta = force - old;
            a.iter_mut().zip(&k.dv).for_each(|(x, r)| *x += r * delta);
            lambda.iter_mut().zip(&k.dlambda).for_each(|(x, r)| *x += r * delta);
            change = change.max(delta.abs());
            scale = scale.max(force.abs());
        }
        if change <= 4.0 * f64::EPSILON * scale.max(f64::MIN_POSITIVE) || (sweep > 0 && change == 0.0) {
            return Ok(());
        }
    }
    Err(DynamicsError::Friction {
        time: t,
        joint: frictions.iter().map(|f| f.name.as_str()).collect::<Vec<_>>().join("', '"),
        what: format!("the friction forces of the joints did not settle in {MAX_SWEEPS} sweeps"),
    })
}

/// Solves `F = base − σ μ |ℓ₀ + ℓ₁ F|` (one solution when `μ|ℓ₁| < 1`) by Newton's method from the
/// fixed-point iterate.
fn newton(base: f64, sign: f64, l0: &[f64; 3], l1: &[f64; 3], mu: f64) -> f64 {
    let norm = |f: f64| (0..3).map(|j| (l0[j] + l1[j] * f).powi(2)).sum::<f64>().sqrt();
    let mut f = base - sign * mu * norm(base);
    for _ in 0..MAX_NEWTON {
        let n = norm(f);
        let phi = f - base + sign * mu * n;
        let dn = if n > 0.0 {
            (0..3).map(|j| (l0[j] + l1[j] * f) * l1[j]).sum::<f64>() / n
        } else {
            0.0
        };
        let step = phi / (1.0 + sign * mu * dn);
        f -= step;
        if step.abs() <= f64::EPSILON * f.abs().max(f64::MIN_POSITIVE) {
            break;
        }
    }
    f
}
