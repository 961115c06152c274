//! The registry of integration methods: every place that offers a choice of method (scenes, the
//! command line, Python, `dalembert trade`, the docs' table) reads [`METHODS`]. A new method is one
//! file under `methods/` that implements [`Stepper`](crate::Stepper) and defines its
//! [`MethodEntry`], plus one line in [`METHODS`].

use crate::methods;
use crate::stepper::{Setup, StepControl, Stepper};
use crate::IntegrationError;
use std::fmt;

/// Most parameters a method may have.
pub const MAX_PARAMETERS: usize = 4;

/// A numeric setting of a method (`rtol`, `rho_inf`): its scene key, keyword and flag
/// (`--rho-inf`) name, default and valid range.
#[derive(Debug)]
pub struct Parameter {
    /// Key in scenes and Python (`rho_inf`); the flag is `--` + the key with `-` for `_`.
    pub key: &'static str,
    /// Value when not given.
    pub default: f64,
    /// What it is, one line.
    pub doc: &'static str,
    /// Valid values.
    pub valid: fn(f64) -> bool,
    /// The rule in words, for messages: "must be positive", "must lie in [0, 1]".
    pub expected: &'static str,
}

/// What `dalembert trade` varies for a method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum TradeAxis {
    /// The grid's steps, with each of the grid's stabilizations (unless the method keeps the
    /// constraints itself).
    Steps,
    /// The grid's tolerances, given to each of these parameters, with projection; steps limited
    /// only by the tolerance.
    Tolerances(&'static [&'static str]),
}

/// Which formulations a method integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Applies {
    /// Any formulation's `q̈(t, q, q̇)`.
    AnyFormulation,
    /// Only the augmented index-3 equations (the formulation reports
    /// [`is_index3_augmented`](dalembert_system::Formulation::is_index3_augmented)); with another
    /// it is refused by name, never silently replaced.
    AugmentedIndex3,
}

impl MethodEntry {
    /// Why this method cannot integrate a formulation named `formulation` whose equations are
    /// (`index3_augmented`) or are not the augmented index-3 system, or `None` when it can. One
    /// message for the run's refusal and for settings checked before a run starts.
    pub fn refuses(&self, formulation: &str, index3_augmented: bool) -> Option<String> {
        (self.applies == Applies::AugmentedIndex3 && !index3_augmented).then(|| {
            format!(
                "{0} integrates the augmented index-3 equations and the {1} formulation has no implicit form of its own yet: use formulation augmented with {0}, or rk4 / dopri5 with {1}",
                self.name, formulation
            )
        })
    }
}

/// A method's constructor: builds its stepper for one run.
pub type Build = fn(&Method, Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError>;

/// A registered method: its names, properties and constructor.
pub struct MethodEntry {
    /// Name in scenes, on the command line, in reports.
    pub name: &'static str,
    /// Other accepted spellings.
    pub aliases: &'static [&'static str],
    /// One line for help texts and the docs' table.
    pub summary: &'static str,
    /// Order of accuracy.
    pub order: u32,
    /// How its steps are chosen.
    pub control: StepControl,
    /// True when the method keeps the position constraints itself: the run's stabilization is
    /// ignored (and a user who sets one is told).
    pub keeps_constraints: bool,
    /// Which formulations it integrates.
    pub applies: Applies,
    /// Its parameters, in order.
    pub parameters: &'static [Parameter],
    /// What `trade` varies.
    pub trade: TradeAxis,
    /// A warning for settings that are valid but risky (`rho_inf = 1`), if any.
    pub advice: fn(&Method) -> Option<String>,
    /// Builds the method for one run.
    pub build: Build,
}

impl fmt::Debug for MethodEntry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MethodEntry")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// Every method, in the order help texts and `trade` list them.
pub static METHODS: &[&MethodEntry] = &[
    &methods::symplectic_euler::ENTRY,
    &methods::rk4::ENTRY,
    &methods::dopri5::ENTRY,
    &methods::generalized_alpha::ENTRY,
    &methods::ali3p::ENTRY,
];

/// The names of [`METHODS`].
pub fn method_names() -> Vec<&'static str> {
    METHODS.iter().map(|e| e.name).collect()
}

/// A method with its parameter values: what [`crate::IntegratorOptions`] integrates with.
/// Typed constructors ([`Method::rk4`], [`Method::dopri5`], …) live with each method; by name,
/// [`Method::named`].
#[derive(Clone, Copy)]
pub struct Method {
    entry: &'static MethodEntry,
    values: [f64; MAX_PARAMETERS],
}

impl Method {
    /// The method of `entry` with its default parameters.
    pub fn of(entry: &'static MethodEntry) -> Self {
        let mut values = [f64::NAN; MAX_PARAMETERS];
        for (v, p) in values.iter_mut().zip(entry.parameters) {
            *v = p.default;
        }
        Method { entry, values }
    }

    /// The registered method called `name` (or one of its aliases), with default parameters.
    pub fn named(name: &str) -> Option<Self> {
        METHODS
            .iter()
            .find(|e| e.name == name || e.aliases.contains(&name))
            .map(|e| Method::of(e))
    }

    /// Its registry entry.
    pub fn entry(&self) -> &'static MethodEntry {
        self.entry
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        self.entry.name
    }

    /// The value of parameter `key`, if the method has it.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.entry
            .parameters
            .iter()
            .position(|p| p.key == key)
            .map(|i| self.values[i])
    }

    /// The same method with parameter `key` set to `value`. Errors (one line): the method has no
    /// such parameter, or the value is out of its range.
    pub fn with(mut self, key: &str, value: f64) -> Result<Self, String> {
        let Some(i) = self.entry.parameters.iter().position(|p| p.key == key) else {
            return Err(format!("{} has no parameter '{key}'", self.name()));
        };
        let p = &self.entry.parameters[i];
        if !(p.valid)(value) {
            return Err(format!("{key} {}, got {value}", p.expected));
        }
        self.values[i] = value;
        Ok(self)
    }

    /// Its parameters with their values.
    pub fn parameters(&self) -> impl Iterator<Item = (&'static Parameter, f64)> + '_ {
        self.entry.parameters.iter().zip(self.values)
    }

    /// The value of the `i`-th parameter (methods read their own by position).
    pub(crate) fn value(&self, i: usize) -> f64 {
        self.values[i]
    }

    /// Sets the `i`-th parameter without checking it (typed constructors; the run checks).
    pub(crate) fn set(&mut self, i: usize, v: f64) {
        self.values[i] = v;
    }

    /// The first parameter whose value is out of range, as a one-line message.
    pub fn check(&self) -> Result<(), String> {
        for (p, v) in self.parameters() {
            if !(p.valid)(v) {
                return Err(format!("{} {}, got {v}", p.key, p.expected));
            }
        }
        Ok(())
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.entry, other.entry)
            && self.parameters().map(|(_, v)| v).eq(other.parameters().map(|(_, v)| v))
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self)
    }
}

/// `rk4`, `dopri5 (rtol 1e-8, atol 1e-10)`, `generalized-alpha (rho_inf 0.8)`.
impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.name())?;
        for (k, (p, v)) in self.parameters().enumerate() {
            write!(f, "{}{} ", if k == 0 { " (" } else { ", " }, p.key)?;
            if v == 0.0 || (1e-3..1e4).contains(&v.abs()) {
                write!(f, "{v}")?;
            } else {
                write!(f, "{v:e}")?;
            }
        }
        if !self.entry.parameters.is_empty() {
            write!(f, ")")?;
        }
        Ok(())
    }
}

/// Parameter validity: positive and finite.
pub(crate) fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// Parameter validity: in `[0, 1]`.
pub(crate) fn unit_interval(v: f64) -> bool {
    (0.0..=1.0).contains(&v)
}

/// For entries without advice.
pub(crate) fn no_advice(_: &Method) -> Option<String> {
    None
}
