//! Changes to a scene's run settings from the command line or from Python keyword arguments,
//! validated once for both (the messages name the flag or the keyword).

use super::{parse_redundancy, unknown_name, IntegratorKind, RunSettings, StabilizationKind, REDUNDANCY_NAMES};
use crate::FormulationKind;

/// How the caller spells a setting's name in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Spelling {
    /// Command-line flags: `--rho-inf`.
    #[default]
    Flags,
    /// Keyword arguments: `rho_inf`.
    Keywords,
}

/// Settings to change; `None` keeps the scene's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOverrides {
    /// `augmented | embedding | amalgamated`.
    pub formulation: Option<String>,
    /// `symplectic-euler | rk4 | dopri5 | generalized-alpha`.
    pub integrator: Option<String>,
    /// Spectral radius at infinity of generalized-α, in [0, 1].
    pub rho_inf: Option<f64>,
    /// Fixed step, or the initial step of dopri5 (s).
    pub step: Option<f64>,
    /// Relative tolerance (dopri5).
    pub rtol: Option<f64>,
    /// Absolute tolerance (dopri5).
    pub atol: Option<f64>,
    /// End time (s).
    pub end: Option<f64>,
    /// Output interval (s).
    pub every: Option<f64>,
    /// `none | baumgarte | projection`.
    pub stabilization: Option<String>,
    /// `error | minimum-norm`.
    pub redundant: Option<String>,
}

impl RunOverrides {
    /// `settings` with these changes, and the warnings they deserve (a setting the chosen
    /// integrator ignores, an undamped generalized-α). Errors are one line naming the setting.
    pub fn apply(&self, settings: &RunSettings, spelling: Spelling) -> Result<(RunSettings, Vec<String>), String> {
        let name = |flag: &str| match spelling {
            Spelling::Flags => format!("--{}", flag.replace('_', "-")),
            Spelling::Keywords => flag.to_string(),
        };
        let mut s = *settings;
        if let Some(f) = &self.formulation {
            s.formulation =
                FormulationKind::parse(f).ok_or_else(|| unknown_name("formulation", f, FormulationKind::NAMES))?;
        }
        if let Some(i) = &self.integrator {
            s.integrator =
                IntegratorKind::parse(i).ok_or_else(|| unknown_name("integrator", i, IntegratorKind::NAMES))?;
        }
        if let Some(r) = self.rho_inf {
            if !(0.0..=1.0).contains(&r) {
                return Err(format!("{} must lie in [0, 1], got {r}", name("rho_inf")));
            }
            s.rho_inf = r;
        }
        if let Some(r) = &self.redundant {
            s.redundancy =
                parse_redundancy(r).ok_or_else(|| unknown_name("redundancy treatment", r, REDUNDANCY_NAMES))?;
        }
        if let Some(st) = &self.stabilization {
            s.stabilization = StabilizationKind::parse(st)
                .ok_or_else(|| unknown_name("stabilization", st, StabilizationKind::NAMES))?;
        }
        for (dst, src, what) in [
            (&mut s.step, self.step, "step"),
            (&mut s.rtol, self.rtol, "rtol"),
            (&mut s.atol, self.atol, "atol"),
            (&mut s.end, self.end, "end"),
            (&mut s.output_every, self.every, "every"),
        ] {
            if let Some(v) = src {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!("{} must be positive, got {v}", name(what)));
                }
                *dst = v;
            }
        }
        let mut warnings = Vec::new();
        let ignored = |flag: &str, used_by: &str| {
            format!(
                "{} applies to {used_by} only; ignored with {}",
                name(flag),
                s.integrator.name()
            )
        };
        if s.integrator != IntegratorKind::Dopri5 {
            if self.rtol.is_some() {
                warnings.push(ignored("rtol", "dopri5"));
            }
            if self.atol.is_some() {
                warnings.push(ignored("atol", "dopri5"));
            }
        }
        if s.integrator != IntegratorKind::GeneralizedAlpha && self.rho_inf.is_some() {
            warnings.push(ignored("rho_inf", "generalized-alpha"));
        }
        if s.integrator == IntegratorKind::GeneralizedAlpha && s.rho_inf > 0.99 {
            warnings.push(format!(
                "rho_inf = {} leaves the index-3 form without numerical damping: the velocity constraints drift and the run can fail (docs/integrators.md); 0.99 or less is stable",
                s.rho_inf
            ));
        }
        if s.integrator == IntegratorKind::GeneralizedAlpha && self.stabilization.is_some() {
            warnings.push(format!(
                "{} is ignored with generalized-alpha (it keeps the position constraints itself)",
                name("stabilization")
            ));
        }
        Ok((s, warnings))
    }
}
