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
//! joint begins to slip within a step without a jump in its force. A friction cone's two elements
//! (a spatial rigid contact's) begin to slip together by maximal dissipation, their force on the
//! bound and anti-parallel to the slip acceleration it leaves ((L14) of `docs/limits.md`).
//!
//! Accelerations and multipliers are affine in the friction forces: `v̇ = v̇₀ + Σ A_k F_k`,
//! `λ = λ₀ + Σ Λ_k F_k`, with `A_k`, `Λ_k` the response of the formulation to a unit generalized
//! force `g_k` (same state, same matrix). So stick is exact: the slip acceleration is zero to
//! round-off and a joint at rest stays at rest. (F1)–(F3) of all elements are solved together
//! by Newton's method ([`solve_friction`]). A slipping element's equation
//! `F = −c w − σ μ |L(λ₀ + Λ F)|` has one solution when `μ |L Λ| < 1`; otherwise the friction
//! force is not determined by the law (a Painlevé configuration), reported as an error naming
//! the joint.

use crate::{DynamicsError, MultibodySystem};

/// The most coordinates a slip row touches (two spatial bodies of six velocities each).
pub const SLIP_ROW_CAPACITY: usize = 12;

/// One friction element of a system, as the system describes it once: a joint's, or a rigid
/// contact's (`docs/limits.md`, "Friction in rigid contact").
#[derive(Debug, Clone, PartialEq)]
pub struct JointFriction {
    /// What the element is, in messages: `"joint"` or `"contact"`.
    pub element: &'static str,
    /// The joint's or contact's name (in errors and outputs).
    pub name: String,
    /// `μ_k`: the friction force per unit of `|L_k λ|` (the Coulomb coefficient for a slider, the
    /// coefficient times the pin radius for a revolute joint, in metres).
    pub coefficient: f64,
    /// `c_k`: viscous friction per unit slip rate (N·s/m or N·m·s/rad).
    pub viscous: f64,
    /// `f₀_k`: a friction force (N) or torque (N·m) that does not depend on the load (a URDF
    /// joint's `<dynamics friction>`, an MJCF joint's `frictionloss`), added to `μ_k N_k`.
    pub constant: f64,
    /// The multiplier rows whose Euclidean norm is the joint's normal load `N_k`.
    pub load_rows: Vec<usize>,
    /// The limit ([`MultibodySystem::limits`]) whose force is the normal load, with the
    /// multiplier rows' if there are any: a rigid contact's friction is loaded by the contact's
    /// normal force, which acts only while the contact is held (the element is
    /// [`Mode::Free`] otherwise).
    pub load_limit: Option<usize>,
    /// `w_s`: the slip rate below which the joint counts as at rest (m/s or rad/s).
    pub stick_speed: f64,
    /// The other element of a friction cone, where this one is one of the two tangent rows of a
    /// spatial rigid contact's friction (`docs/limits.md`, "Friction in spatial rigid contact"):
    /// the two forces are then bounded together, `|(F_k, F_cone)| ≤ μ N`, and slip against the
    /// slip velocity's direction in the tangent plane. `None` for a scalar element.
    pub cone: Option<usize>,
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

/// The fraction of the stick speed by which a slip's rate passes zero at its event
/// ([`Mode::event`]).
pub const SLIP_END: f64 = 1e-3;

/// What a friction element does over a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// At rest (its slip rate within the stick speed): (F2), or (F3) where (F2) cannot hold it.
    Stick,
    /// Slipping in the direction of the sign (±1): (F1). For an element of a friction cone
    /// ([`JointFriction::cone`]), the component along its row of the cone's reference direction
    /// `d`, a unit vector in the tangent plane set where the slip begins or turns: the slip's
    /// event is `d·w` passing zero, and the force follows the slip velocity itself
    /// ([`FrictionTerms::along`]).
    Slip(f64),
    /// A joint limit's element away from its bounds: no force (`docs/limits.md`, (L1)).
    Free,
    /// A joint limit's element held at a bound, its force `F` with `σ F ≥ 0` for the sign `σ`
    /// (`+1` at the lower bound, `−1` at the upper): (L2), or no force where holding would pull.
    Held(f64),
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
    /// sign change ends it: `σ w + 10⁻³ w_s` for a slip (its rate passes zero by a thousandth of
    /// the stick speed, so that a slip that begins at rest, its rate zero to round-off, starts
    /// clear of its event), `w_s − |w|` for a stuck joint (its rate leaves the stick speed).
    pub fn event(self, w: f64, stick_speed: f64) -> f64 {
        match self {
            Mode::Stick => stick_speed - w.abs(),
            Mode::Slip(sign) => sign * w + SLIP_END * stick_speed,
            // A limit's events are the switching formulation's ([`crate::Frictional`]).
            Mode::Free | Mode::Held(_) => 1.0,
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
    /// The direction (±1) a stuck element that (F2) cannot hold begins to slip in (0 otherwise).
    pub direction: f64,
    /// The force that would hold a stuck or held element (`ẇ = 0`) at the last evaluation.
    pub hold: f64,
    /// True for an element that has just come to stick (at the start, where its slip stopped, or
    /// where its contact came to rest), held at the first Newton iterate of the next evaluation.
    pub fresh: bool,
    /// For an element of a slipping friction cone, the component along its row of the direction
    /// (F1) opposes at this evaluation (the slip velocity's, `docs/limits.md`, "Friction in
    /// spatial rigid contact"), used instead of the mode's; `None` otherwise.
    pub along: Option<f64>,
    /// True when the element's force is given: already in the `a` and `λ` that
    /// [`solve_friction`] starts from, which leaves it as it is and reads neither its row's
    /// coupling nor its response (a slipping element in [`crate::Frictional`]'s iteration on the
    /// slipping elements' forces).
    pub given: bool,
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
            direction: 0.0,
            hold: 0.0,
            fresh: false,
            along: None,
            given: false,
        }
    }
}

/// The largest number of Newton iterations of [`solve_friction`].
const MAX_ITERATIONS: usize = 60;

/// The iterations after which a stuck element's law may change only from holding to slipping,
/// and a cone's flips between (L14) and the projection on its bound are damped.
const SETTLING: usize = 12;

/// The share of its bound by which a cone that followed (L14) must be inside it to hold again.
const ONSET_MARGIN: f64 = 1e-9;

/// Work space of [`solve_friction`] for `K` elements and `m` multipliers.
#[derive(Debug, Clone)]
pub struct FrictionWork {
    /// `W_kj = g_k·A_j` (row-major, `K × K`).
    coupling: Vec<f64>,
    /// The elements whose forces are found (not a free limit, not given): the rows and columns
    /// of `coupling`, `jacobian` and the entries of the vectors below, in this order.
    active: Vec<usize>,
    /// Newton matrix (row-major, `K × K`).
    jacobian: Vec<f64>,
    /// Residuals, then the Newton step.
    residual: Vec<f64>,
    /// `ẇ₀ = g·v̇₀ + b` without friction.
    alpha0: Vec<f64>,
    /// `λ(F)`.
    lambda: Vec<f64>,
    /// Each element's law in the last iteration: true where (F2) holds it.
    holding: Vec<bool>,
    /// True where a cone's element followed (L14) in the last iteration ([`Law::Onset`]).
    onset: Vec<bool>,
    /// The Newton matrix and residuals kept for [`minimum_norm_step`], and its `J Jᵀ`.
    copy: Vec<f64>,
    rhs: Vec<f64>,
    gram: Vec<f64>,
    /// The forces the Newton step starts from.
    start: Vec<f64>,
    /// Work space of [`least_norm`].
    scratch: Vec<f64>,
    /// The slip direction of each element in the last iteration (0 where held).
    direction: Vec<f64>,
    /// `ẇ` of each element at the iterate.
    alpha: Vec<f64>,
    /// The position in `active` of each active element's cone partner ([`JointFriction::cone`]),
    /// `usize::MAX` for a scalar element.
    partner: Vec<usize>,
    /// The pull a held limit may take and stay held (N or N·m): [`RELEASE_SHARE`] of the
    /// evaluation's largest force, so that a stop whose force is zero to round-off (a gripper's
    /// two fingers pushed alike) is not let go and struck again at every step.
    pub adhesion: f64,
}

/// The share of an evaluation's largest multiplier or element force that a held limit may pull
/// with and stay held (`docs/limits.md`, (L2)): far above the round-off of a force that is zero
/// (1e-15 of the largest), far below any force that moves a joint measurably.
pub const RELEASE_SHARE: f64 = 1e-10;

impl FrictionWork {
    /// Storage for `k` elements and `m` multipliers.
    pub fn new(k: usize, m: usize) -> Self {
        FrictionWork {
            coupling: vec![0.0; k * k],
            active: Vec::with_capacity(k),
            jacobian: vec![0.0; k * k],
            residual: vec![0.0; k],
            alpha0: vec![0.0; k],
            lambda: vec![0.0; m],
            holding: vec![false; k],
            onset: vec![false; k],
            copy: vec![0.0; k * k],
            rhs: vec![0.0; k],
            gram: vec![0.0; k * k],
            start: vec![0.0; k],
            scratch: vec![0.0; k],
            direction: vec![0.0; k],
            alpha: vec![0.0; k],
            partner: Vec::with_capacity(k),
            adhesion: 0.0,
        }
    }
}

/// The friction bound `μ_k N_k + f₀_k` of `spec` at the multipliers `lambda`, and its
/// gradient's direction: `∂(μ N)/∂λ = (μ / N) L_kᵀ L_k λ`, kept as the factor `μ / N` (zero at
/// `N = 0`) over the load rows' multipliers, so that its product with each response costs the
/// load rows' length and no division.
struct Load {
    bound: f64,
    factor: f64,
}

impl Load {
    /// The load under the multipliers `lambda` and the force `limit` of the element's load limit
    /// (zero without one).
    fn at(spec: &JointFriction, lambda: &[f64], limit: f64) -> Load {
        let norm = (spec.load_rows.iter().map(|&r| lambda[r] * lambda[r]).sum::<f64>() + limit * limit).sqrt();
        Load {
            bound: spec.constant + spec.coefficient * norm,
            factor: if norm == 0.0 { 0.0 } else { spec.coefficient / norm },
        }
    }

    /// The bound's change along the multipliers' change `dl` and the load limit's `(force,
    /// change)`.
    fn change(&self, spec: &JointFriction, lambda: &[f64], dl: &[f64], limit: (f64, f64)) -> f64 {
        self.factor * (spec.load_rows.iter().map(|&r| lambda[r] * dl[r]).sum::<f64>() + limit.0 * limit.1)
    }
}

/// The force of `spec`'s load limit among `terms` (the friction elements first, `frictions` of
/// them, then the limits), and the index of its element; zero and `usize::MAX` without one.
fn limit_load(spec: &JointFriction, terms: &[FrictionTerms], frictions: usize) -> (f64, usize) {
    match spec.load_limit {
        Some(l) => terms
            .get(frictions + l)
            .map_or((0.0, usize::MAX), |t| (t.force, frictions + l)),
        None => (0.0, usize::MAX),
    }
}

/// Solves (F1)–(F3) for every friction element in its mode, and (L1)–(L2) of
/// `docs/limits.md` for every joint limit after them: on entry `acc`, `lambda` are the
/// frictionless `v̇₀`, `λ₀` (with the given forces' part, [`FrictionTerms::given`]) and
/// `terms[k]` hold the rows, responses and modes (the friction elements of
/// [`MultibodySystem::frictions`] first, then the limits of [`MultibodySystem::limits`]; a free
/// limit's response and a given element's are not read); on exit `acc`, `lambda` include the
/// forces, and `terms[k].force`, `terms[k].sticks` say what each element does. The Newton
/// system is the size of the elements whose forces are found.
///
/// The forces couple through the accelerations (`ẇ = ẇ₀ + W F`, `W_kj = g_k·A_j`) and the loads
/// (`λ = λ₀ + Σ Λ_j F_j`), so the equations are solved together by Newton's method: a held
/// element's row is `ẇ_k = 0`, a slipping one's `F_k + c_k w_k + σ N_k(F) = 0`, a free limit's
/// `F_k = 0`; which law a stuck element follows (F2 or F3), and whether a held limit holds or
/// lets go (its force would pull), is decided at each iterate by its holding force; the
/// iteration ends when the laws stop changing and the step is at round-off. Allocates nothing.
pub fn solve_friction(
    system: &dyn MultibodySystem,
    t: f64,
    v: &[f64],
    (acc, lambda): (&mut [f64], &mut [f64]),
    terms: &mut [FrictionTerms],
    work: &mut FrictionWork,
) -> Result<(), DynamicsError> {
    let frictions = system.frictions();
    let limits = system.limits();
    let name = |k: usize| -> &str {
        if k < frictions.len() {
            &frictions[k].name
        } else {
            limits.get(k - frictions.len()).map_or("?", |l| l.name.as_str())
        }
    };
    let fail = |k: usize, what: String| {
        if k < frictions.len() {
            DynamicsError::Friction {
                time: t,
                joint: format!("{} '{}'", frictions[k].element, name(k)),
                what,
            }
        } else {
            let element = limits.get(k - frictions.len()).map_or("joint", |l| l.element);
            DynamicsError::Limit {
                time: t,
                element: format!("{element} '{}'", name(k)),
                what,
            }
        }
    };
    let all = |what: String, active: &[usize]| {
        let names = active.iter().map(|&k| name(k)).collect::<Vec<_>>().join("', '");
        let joints = active
            .iter()
            .all(|&k| k >= frictions.len() || frictions[k].element == "joint");
        let element = match active {
            [k] => frictions.get(*k).map_or("joint", |f| f.element),
            _ if joints => "joints",
            _ => "elements",
        };
        DynamicsError::Friction {
            time: t,
            joint: format!("{element} '{names}'"),
            what,
        }
    };
    // The elements whose forces are found: not a free limit (no force) and not given.
    work.active.clear();
    for (k, term) in terms.iter_mut().enumerate() {
        if term.mode == Mode::Free || term.given {
            if !term.given {
                term.force = 0.0;
            }
            term.sticks = false;
            term.direction = 0.0;
            term.hold = 0.0;
        } else {
            work.active.push(k);
        }
    }
    let n = work.active.len();
    if n == 0 {
        // Nothing to solve (what the iteration below would find, without its two solves).
        return Ok(());
    }
    work.partner.clear();
    for a in 0..n {
        let cone = frictions.get(work.active[a]).and_then(|f| f.cone);
        let at = cone.and_then(|p| work.active.iter().position(|&j| j == p));
        work.partner.push(at.unwrap_or(usize::MAX));
    }
    for a in 0..n {
        let term = &terms[work.active[a]];
        work.alpha0[a] = term.row.dot(acc) + term.row.bias;
        for b in 0..n {
            work.coupling[a * n + b] = term.row.dot(&terms[work.active[b]].dv);
        }
        let d = work.coupling[a * n + a];
        if !(d > 0.0 && d.is_finite()) {
            return Err(fail(
                work.active[a],
                format!("a force along the joint does not move it (its response is {d:e})"),
            ));
        }
    }
    // From the last evaluation's forces (the stages of a step are near each other, so Newton's
    // method starts close).
    for &k in &work.active {
        if !terms[k].force.is_finite() {
            terms[k].force = 0.0;
        }
    }
    work.holding.iter_mut().for_each(|h| *h = false);
    work.onset.iter_mut().for_each(|o| *o = false);
    let largest = lambda
        .iter()
        .chain(terms.iter().map(|t| &t.force))
        .fold(0.0f64, |m, x| m.max(x.abs()));
    work.adhesion = RELEASE_SHARE * largest;
    // True when the last step solved linear equations exactly (every law `ẇ = 0` or `F = 0`,
    // by the LU): if the laws stay, the forces are their solution, without another solve.
    let mut exact = false;
    // The last Newton step's size (the iteration's rate, below).
    let mut last_step = f64::INFINITY;
    for iteration in 0..MAX_ITERATIONS {
        // λ(F) and the residuals and Newton matrix at F.
        work.lambda.copy_from_slice(lambda);
        for &k in &work.active {
            let term = &terms[k];
            work.lambda
                .iter_mut()
                .zip(&term.dlambda)
                .for_each(|(l, d)| *l += d * term.force);
        }
        let mut changed = false;
        // True where a cone's law changed between (L14) and the projection on its bound.
        let mut flipped = false;
        let mut linear = true;
        let mut scale = 0.0f64;
        // Each element's slip acceleration at the iterate, and the force that would hold it with
        // the others' kept; a cone's two elements are held together (the 2 × 2 block of their
        // coupling).
        for a in 0..n {
            let row = a * n;
            work.alpha[a] = work.alpha0[a]
                + (0..n)
                    .map(|b| work.coupling[row + b] * terms[work.active[b]].force)
                    .sum::<f64>();
            terms[work.active[a]].hold = terms[work.active[a]].force - work.alpha[a] / work.coupling[row + a];
        }
        for a in 0..n {
            let b = work.partner[a];
            if b < n && b > a {
                let (w_aa, w_ab, w_ba, w_bb) = (
                    work.coupling[a * n + a],
                    work.coupling[a * n + b],
                    work.coupling[b * n + a],
                    work.coupling[b * n + b],
                );
                let det = w_aa * w_bb - w_ab * w_ba;
                if det > 0.0 {
                    let (ra, rb) = (work.alpha[a], work.alpha[b]);
                    let (ka, kb) = (work.active[a], work.active[b]);
                    terms[ka].hold = terms[ka].force - (w_bb * ra - w_ab * rb) / det;
                    terms[kb].hold = terms[kb].force - (w_aa * rb - w_ba * ra) / det;
                }
            }
        }
        for a in 0..n {
            let k = work.active[a];
            let row = a * n;
            let alpha = work.alpha[a];
            let hold = terms[k].hold;
            // After `SETTLING` iterations an element found unable to hold stays so: the laws
            // then change only one way and the iteration ends (a joint grazing the limit of its
            // friction can make the laws cycle).
            let stays_loose = iteration >= SETTLING && !work.holding[a];
            let law = match terms[k].mode {
                Mode::Free => Law::Zero,
                Mode::Held(sign) => {
                    if sign * hold >= -work.adhesion && !stays_loose {
                        Law::Hold
                    } else {
                        Law::Zero
                    }
                }
                Mode::Slip(sign) => Law::Slip(terms[k].along.unwrap_or(sign)),
                Mode::Stick => {
                    let (limit, _) = limit_load(&frictions[k], terms, frictions.len());
                    let bound = Load::at(&frictions[k], &work.lambda, limit).bound;
                    // An element that has just come to stick is held at the first iterate, so that
                    // its law is decided on forces found together: where stuck elements are
                    // redundant (two corners of a block on a floor) each one's holding force with
                    // the others' left as they were is not its share, and would leave them
                    // pulling against each other at their bounds.
                    // A cone's bound is on the norm of its two forces, and it slips against
                    // their direction.
                    let partner = work.partner[a];
                    let size = if partner < n {
                        hold.hypot(terms[work.active[partner]].hold)
                    } else {
                        hold.abs()
                    };
                    // A cone that followed (L14) holds again only where its holding force is
                    // inside the bound by more than round-off: on the bound with its slip
                    // acceleration at round-off, either law is a solution, and the holding one's
                    // least-norm step leaves the bound (with redundant holds, by far).
                    let inside = if work.onset[a] {
                        size <= bound * (1.0 - ONSET_MARGIN)
                    } else {
                        size <= bound
                    };
                    if ((iteration == 0 && terms[k].fresh) || inside) && !stays_loose {
                        Law::Hold
                    } else if partner < n
                        && onset_ready(
                            (terms[k].force, terms[work.active[partner]].force),
                            (alpha, work.alpha[partner]),
                            (
                                bound,
                                work.coupling[a * n + a].max(work.coupling[partner * n + partner]),
                            ),
                        )
                    {
                        Law::Onset(partner)
                    } else if stays_loose && work.direction[a] != 0.0 {
                        Law::Slip(work.direction[a])
                    } else if partner < n {
                        Law::Slip(-hold / size)
                    } else {
                        Law::Slip(-hold.signum())
                    }
                }
            };
            let holding = law == Law::Hold;
            linear &= matches!(law, Law::Hold | Law::Zero);
            work.direction[a] = match law {
                Law::Slip(sign) => sign,
                Law::Onset(b) => {
                    let (fa, fb) = (terms[k].force, terms[work.active[b]].force);
                    -fa / fa.hypot(fb)
                }
                _ => 0.0,
            };
            changed |= holding != work.holding[a];
            work.holding[a] = holding;
            let onset = matches!(law, Law::Onset(_));
            flipped |= onset != work.onset[a];
            work.onset[a] = onset;
            let term = &terms[k];
            match law {
                Law::Hold => {
                    work.residual[a] = alpha;
                    work.jacobian[row..row + n].copy_from_slice(&work.coupling[row..row + n]);
                    scale = scale.max(term.force.abs());
                }
                Law::Zero => {
                    work.residual[a] = term.force;
                    for b in 0..n {
                        work.jacobian[row + b] = if b == a { 1.0 } else { 0.0 };
                    }
                }
                Law::Onset(b) => {
                    // (F3) of a cone by maximal dissipation: the force on the cone's bound and
                    // anti-parallel to the slip acceleration it leaves (`docs/limits.md`, (L14)).
                    // The first of the two rows is the bound, the second the cross product.
                    let spec = &frictions[k];
                    let (limit, at) = limit_load(spec, terms, frictions.len());
                    let load = Load::at(spec, &work.lambda, limit);
                    let (fa, fb) = (term.force, terms[work.active[b]].force);
                    let size = fa.hypot(fb);
                    scale = scale.max(size).max(load.bound);
                    if a < b {
                        work.residual[a] = size - load.bound;
                        for c in 0..n {
                            let other = &terms[work.active[c]];
                            let own = if work.active[c] == at { 1.0 } else { 0.0 };
                            let norm = if c == a {
                                fa / size
                            } else if c == b {
                                fb / size
                            } else {
                                0.0
                            };
                            work.jacobian[row + c] =
                                norm - load.change(spec, &work.lambda, &other.dlambda, (limit, own));
                        }
                    } else {
                        // Row `a` is the cone's second: `ẇ_b F_a − ẇ_a F_b = 0` (here `b` is the
                        // first row).
                        let first = work.alpha[b];
                        work.residual[a] = first * fa - alpha * fb;
                        for c in 0..n {
                            let mut j = work.coupling[b * n + c] * fa - work.coupling[row + c] * fb;
                            if c == a {
                                j += first;
                            }
                            if c == b {
                                j -= alpha;
                            }
                            work.jacobian[row + c] = j;
                        }
                    }
                }
                Law::Slip(sign) => {
                    let spec = &frictions[k];
                    let (limit, at) = limit_load(spec, terms, frictions.len());
                    let load = Load::at(spec, &work.lambda, limit);
                    let w = term.row.dot(v);
                    work.residual[a] = term.force + spec.viscous * w + sign * load.bound;
                    for b in 0..n {
                        let e = if b == a { 1.0 } else { 0.0 };
                        let other = &terms[work.active[b]];
                        let own = if work.active[b] == at { 1.0 } else { 0.0 };
                        work.jacobian[row + b] =
                            e + sign * load.change(spec, &work.lambda, &other.dlambda, (limit, own));
                    }
                    scale = scale.max(term.force.abs()).max(load.bound);
                    let slope = load.change(spec, &work.lambda, &term.dlambda, (limit, 0.0)).abs();
                    if slope >= 1.0 {
                        return Err(fail(
                            k,
                            format!(
                                "the friction force is not determined by Coulomb's law (Painlevé): μ × the load's \
                                 change per unit friction force is {slope:.3} ≥ 1"
                            ),
                        ));
                    }
                }
            }
        }
        if exact && linear && !changed {
            break;
        }
        work.copy[..n * n].copy_from_slice(&work.jacobian[..n * n]);
        work.rhs[..n].copy_from_slice(&work.residual[..n]);
        for a in 0..n {
            work.start[a] = terms[work.active[a]].force;
        }
        // A matrix singular but for round-off (redundant holds: two corners of an edge level to
        // the integration's error) passes the LU's pivot test, and its step then runs along the
        // redundant forces (measured: steps of 1 to 4 N at residuals of 1e-15, iterate after
        // iterate); it is treated as singular.
        let solved = solve_dense(&mut work.jacobian[..n * n], &mut work.residual[..n], n)
            && determined(&work.residual[..n], &work.copy[..n * n], &work.rhs[..n]);
        exact = linear && solved;
        // After `SETTLING` iterations with the laws kept, the step of least weighted norm: the
        // least-norm forces of each linearization move along the redundant forces where a
        // cone's bound curves them (two cones of an edge, or four of a face, on their bounds
        // with no slip acceleration, measured: the iterates wandered to the 60th iteration).
        let least_step = iteration >= SETTLING && !changed && !flipped;
        if !solved && !minimum_norm_step(work, n, frictions.len(), least_step) {
            let what = "the friction and limit forces of these joints are not determined (their joints move together)";
            // Name the elements that hold (a stop or a sticking joint): theirs are the forces in
            // question; when only stops hold, say so.
            let held: Vec<usize> = (0..n).filter(|&a| work.holding[a]).map(|a| work.active[a]).collect();
            if !held.is_empty() && held.iter().all(|&k| k >= frictions.len()) {
                let names: Vec<&str> = held.iter().map(|&k| name(k)).collect();
                return Err(DynamicsError::Limit {
                    time: t,
                    element: format!("joints '{}'", names.join("', '")),
                    what: "their forces are not determined (their joints move together, as a coupling or a loop makes them)".into(),
                });
            }
            return Err(all(what.into(), &work.active));
        }
        let step = (0..n).map(|a| work.residual[a].abs()).fold(0.0f64, f64::max);
        // Ended at round-off; or where the steps stop shrinking (by less than half) below 10⁻⁹
        // of the largest force, which Newton's method does only where its matrix is nearly
        // singular (redundant holds beside a cone at the bound it just cannot hold, (L14) of
        // `docs/limits.md`): its residuals are then at round-off and the steps are that
        // round-off over the matrix's smallest singular value.
        let scale = scale.max(f64::MIN_POSITIVE);
        let stalled = step <= 1e-9 * scale && step > 0.5 * last_step;
        // After `SETTLING` iterations, a step is halved where a cone's law flipped between
        // (L14) and the projection on its bound, or where, the laws kept, the full steps stopped
        // shrinking above that round-off: each law's Newton step can lead to the other's side,
        // and a load `μ |N|` has a kink where a held contact's normal force `N` is zero; the full
        // steps then cycle between two iterates (two cones of a box's edge beginning to slip; a
        // corner's cone slipping on a normal force of 1e-9 of the box's others, measured). A
        // held contact whose force changes sign on such a step lets go (it then stays loose):
        // its force cycled inside the band it may pull with, so the pull never showed
        // (`docs/limits.md`, (L14)); halving alone left three iterates cycling.
        let cycling = iteration >= SETTLING && !changed && step > 0.5 * last_step && !stalled;
        let damping = if cycling || (iteration >= SETTLING && flipped) {
            0.5
        } else {
            1.0
        };
        for a in 0..n {
            let k = work.active[a];
            let next = terms[k].force - damping * work.residual[a];
            if cycling && work.holding[a] && matches!(terms[k].mode, Mode::Held(_)) && next * terms[k].force < 0.0 {
                work.holding[a] = false;
            }
            terms[k].force = next;
        }
        last_step = step;
        if iteration > 0 && !changed && (step <= 1e-13 * scale || stalled) {
            break;
        }
        if iteration + 1 == MAX_ITERATIONS {
            return Err(all(
                format!("the friction and limit forces did not settle in {MAX_ITERATIONS} iterations"),
                &work.active,
            ));
        }
    }
    for a in 0..n {
        let k = work.active[a];
        let term = &mut terms[k];
        if !term.force.is_finite() {
            return Err(fail(k, "the force along the joint is not finite".into()));
        }
        term.sticks = work.holding[a];
        term.direction = match (term.mode, term.sticks) {
            (Mode::Stick, false) => work.direction[a],
            _ => 0.0,
        };
        if term.force == 0.0 {
            continue;
        }
        acc.iter_mut().zip(&term.dv).for_each(|(x, r)| *x += r * term.force);
        lambda
            .iter_mut()
            .zip(&term.dlambda)
            .for_each(|(x, r)| *x += r * term.force);
    }
    Ok(())
}

/// The Newton step from forces `F₀` (`work.start`) where the Newton matrix `J` is singular (`J`
/// and the residuals `r` in `work.copy`, `work.rhs`; the step into `work.residual`, as
/// [`solve_dense`] leaves it): the forces `F` of the linearized equations `J F = J F₀ − r` of least
/// weighted norm ((L8) of `docs/limits.md`, by [`weighted_least_norm`]), the step `F₀ − F`. `J`
/// is singular where elements that hold are redundant: two corners of a block stuck on a floor
/// hold one motion, so only the sum of their friction forces is determined (two stops held on
/// one motion, only the sum of theirs); the least-norm split is the one redundant joints'
/// reactions get (`docs/sign-conventions.md`), and it does not depend on the forces the
/// iteration starts from. With `least_step`, the step `Δ` of least weighted norm with
/// `J Δ = r` instead (where a cone's curved bound moves the least-norm forces of each
/// linearization, the iteration then ends on a split that depends on its iterate). False where
/// even that fails.
fn minimum_norm_step(work: &mut FrictionWork, n: usize, frictions: usize, least_step: bool) -> bool {
    if !least_step {
        for a in 0..n {
            let j = &work.copy[a * n..(a + 1) * n];
            work.rhs[a] = (0..n).map(|c| j[c] * work.start[c]).sum::<f64>() - work.rhs[a];
        }
    }
    let active = &work.active;
    let scratch = (&mut work.gram[..n * n], &mut work.scratch[..n]);
    if !weighted_least_norm(
        &mut work.copy[..n * n],
        &mut work.rhs[..n],
        (n, |c| active[c] < frictions),
        scratch,
        &mut work.residual[..n],
    ) {
        return false;
    }
    if !least_step {
        for c in 0..n {
            work.residual[c] = work.start[c] - work.residual[c];
        }
    }
    true
}

/// The solution `x` of `A x = b` (`A` row-major `n × n`, singular where the elements that hold
/// are redundant) of least weighted norm, `Σ x_limit² + Σ (x_friction / FRICTION_WEIGHT)²` over
/// the unknowns `c` for which `friction(c)` holds and the others ((L8) of `docs/limits.md`): the
/// columns of the friction elements scaled by [`FRICTION_WEIGHT`], `x = D y` with `y` of least
/// norm by [`least_norm`]. The split of redundant forces ([`minimum_norm_step`]) and of redundant
/// impulses (an impact or a stopping slip where held contacts are redundant) alike, so that both
/// leave a body the normal forces can hold by them. `A` is scaled in place; `b`, `gram` (`n × n`)
/// and `scratch` (`n`) are overwritten. False where it is not finite.
pub(crate) fn weighted_least_norm(
    a: &mut [f64],
    b: &mut [f64],
    (n, friction): (usize, impl Fn(usize) -> bool),
    scratch: (&mut [f64], &mut [f64]),
    x: &mut [f64],
) -> bool {
    let weight = |c: usize| if friction(c) { FRICTION_WEIGHT } else { 1.0 };
    for r in 0..n {
        for c in 0..n {
            a[r * n + c] *= weight(c);
        }
    }
    if !least_norm(&a[..n * n], b, n, scratch, x) {
        return false;
    }
    for (c, out) in x.iter_mut().enumerate().take(n) {
        *out *= weight(c);
    }
    true
}

/// The weight of a friction force against a limit's in [`weighted_least_norm`]'s split where the
/// elements that hold are redundant (`docs/limits.md`, "Friction in spatial rigid contact"): the
/// split minimizes `Σ F_limit² + Σ (F_friction / FRICTION_WEIGHT)²`, so contacts that can hold a
/// body by their normal forces alone do so, their friction taking a hundredth of the share the
/// plain least norm would give it (a ball wedged between three spheres: with the plain split its
/// friction took 1.13 times the normal force, beyond any cone below that, and it slid out of a
/// pocket that holds it without friction).
const FRICTION_WEIGHT: f64 = 0.1;

/// The least-norm solution `x` of `A x = b` (`A` row-major `n × n`, singular where rows are
/// redundant), by iterated Tikhonov regularization: `x ← x + Aᵀ (A Aᵀ + δ I)⁻¹ (b − A x)` from
/// `x = 0`, three times, `δ` 10⁻¹³ of `A Aᵀ`'s largest diagonal entry. Each pass leaves `δ / s²`
/// of the error along a singular value `s` of `A` (three passes: round-off where `s²` is within
/// 10⁴ of the largest), and adds nothing along the directions of zero singular values, whatever
/// the round-off in `b`: it converges to `A⁺ b`. `b`, `gram` (`n × n`) and `scratch` (`n`) are
/// overwritten. False where it is not finite.
fn least_norm(a: &[f64], b: &mut [f64], n: usize, (gram, scratch): (&mut [f64], &mut [f64]), x: &mut [f64]) -> bool {
    scratch[..n].copy_from_slice(&b[..n]);
    x[..n].iter_mut().for_each(|v| *v = 0.0);
    for _ in 0..3 {
        for r in 0..n {
            b[r] = scratch[r] - (0..n).map(|c| a[r * n + c] * x[c]).sum::<f64>();
            for c in 0..n {
                gram[r * n + c] = (0..n).map(|k| a[r * n + k] * a[c * n + k]).sum();
            }
        }
        let largest = (0..n).map(|r| gram[r * n + r]).fold(0.0f64, f64::max);
        if !(largest > 0.0 && largest.is_finite()) {
            return false;
        }
        for r in 0..n {
            gram[r * n + r] += 1e-13 * largest;
        }
        if !solve_dense(gram, b, n) {
            return false;
        }
        for (c, out) in x.iter_mut().enumerate().take(n) {
            *out += (0..n).map(|r| a[r * n + c] * b[r]).sum::<f64>();
        }
    }
    x[..n].iter().all(|v| v.is_finite())
}

/// The force (F1) of friction element `spec` slipping in direction `sign` at slip rate `w`
/// under the multipliers `lambda` and its load limit's force `limit` (zero without one):
/// `−c w − σ (μ N + f₀)`.
pub fn slip_force(spec: &JointFriction, sign: f64, w: f64, lambda: &[f64], limit: f64) -> f64 {
    -spec.viscous * w - sign * Load::at(spec, lambda, limit).bound
}

/// The friction bound `μ N + f₀` of `spec` under the multipliers `lambda` and its load limit's
/// force `limit` (zero without one).
pub fn friction_bound(spec: &JointFriction, lambda: &[f64], limit: f64) -> f64 {
    Load::at(spec, lambda, limit).bound
}

/// The law an element follows at one Newton iterate.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Law {
    /// `ẇ = 0`.
    Hold,
    /// `F = 0`.
    Zero,
    /// (F1) in the direction of the sign.
    Slip(f64),
    /// A cone's (F3) where it cannot hold, with its other element at the given position of the
    /// active ones: the two forces on the bound `μ N`, anti-parallel to the slip acceleration
    /// they leave (maximal dissipation; `docs/limits.md`, (L14)).
    Onset(usize),
}

/// True where a cone's forces `f` are near enough its bound to be iterated by [`Law::Onset`]
/// (whose first row, `|F| − μ N`, has no direction at `F = 0`), from half the bound, and do not
/// feed the slip acceleration `alpha` they leave: `ẇ = −s F` with `s ≥ 0` at the solution, where
/// `s = −ẇ·F / |F|²`; the cross product's other root, `s < 0`, would. Iterates near a bound the
/// cone just cannot hold (`s` near zero) scatter around it by their error, so `s` down to
/// `−10⁻³` of the cone's largest self-coupling `w` (`(bound, w)`) is taken; otherwise (F3)
/// along the holding force (the Euclidean projection on the bound) brings the forces there
/// first.
fn onset_ready(f: (f64, f64), alpha: (f64, f64), (bound, w): (f64, f64)) -> bool {
    let size = f.0.hypot(f.1);
    let s = -(alpha.0 * f.0 + alpha.1 * f.1) / (size * size);
    bound > 0.0 && size >= 0.5 * bound && s >= -1e-3 * w
}

/// The largest `|x| |A| / |b|` (largest entries) at which [`determined`] takes the solution `x`
/// of `A x = b` from an LU: at most the condition number of `A` where the right-hand side
/// determines `x` (a body 10⁸ times heavier than another among the elements), 10¹¹ and more where
/// the redundant part of rows redundant but for round-off took it (an edge level to 10⁻¹⁰ rad:
/// measured 9e6 to 2.5e12 for the impulses that stop its corners' slips).
pub(crate) const CONDITION_LIMIT: f64 = 1e8;

/// True where `x`, an LU's solution of `A x = b` (`A` row-major, `b` the right-hand side), is
/// determined by `b`: `|x| |A| ≤` [`CONDITION_LIMIT`] `|b|` (largest entries). False where the
/// matrix is singular but for round-off, so that the solution carries a large part along the
/// directions it nearly does not see; the least-norm split decides there.
pub(crate) fn determined(x: &[f64], a: &[f64], b: &[f64]) -> bool {
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    largest(x) * largest(a) <= CONDITION_LIMIT * largest(b)
}

/// Solves `A x = b` in place (`A` row-major `n × n`, overwritten by its LU factors; `b` by `x`)
/// by Gaussian elimination with partial pivoting. False when `A` is singular.
pub(crate) fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    let a = &mut a[..n * n];
    let largest = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for c in 0..n {
        let (mut p, mut pivot) = (c, a[c * n + c].abs());
        for i in c + 1..n {
            let v = a[i * n + c].abs();
            if v > pivot || v.is_nan() {
                (p, pivot) = (i, v);
            }
        }
        if pivot.is_nan() || pivot <= 1e-14 * largest {
            return false;
        }
        if p != c {
            // The columns left of `c` are not read again (the right-hand side is eliminated
            // alongside), so only the rest of the rows is swapped.
            for j in c..n {
                a.swap(c * n + j, p * n + j);
            }
            b.swap(c, p);
        }
        let (upper, lower) = a.split_at_mut((c + 1) * n);
        let pivot_row = &upper[c * n + c..c * n + n];
        let bc = b[c];
        for (i, row) in lower.chunks_exact_mut(n).enumerate() {
            let row = &mut row[c..];
            let f = row[0] / pivot_row[0];
            if f != 0.0 {
                for (x, y) in row.iter_mut().zip(pivot_row) {
                    *x -= f * y;
                }
                b[c + 1 + i] -= f * bc;
            }
        }
    }
    for c in (0..n).rev() {
        let row = &a[c * n..c * n + n];
        let s: f64 = (c + 1..n).map(|j| row[j] * b[j]).sum();
        b[c] = (b[c] - s) / row[c];
    }
    b.iter().all(|x| x.is_finite())
}
