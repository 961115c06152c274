//! MJCF actuators (`docs/import.md`, "MJCF"): `motor`, `position`, `velocity`, and `general`
//! with a fixed gain and an affine bias, read into one law. MuJoCo's actuator force is
//! `f = g ū + b₀ + b₁ l + b₂ l̇` with `ū` the control held in `ctrlrange`, `l = gear q` and
//! `l̇ = gear q̇` the actuator's length and rate; `f` is held in `forcerange`, and the joint gets
//! `gear f`. The shortcuts set `g` and `b`: a motor `g = 1`; a position servo `g = kp`,
//! `b₁ = −kp`, `b₂ = −kv`; a velocity servo `g = kv`, `b₂ = −kv`.

use super::Reader;
use crate::scene::SceneError;
use roxmltree::Node;

/// The actuator elements read.
const ACTUATORS: [&str; 4] = ["motor", "position", "velocity", "general"];

/// The MuJoCo actuator elements outside the subset (refused by name).
const OTHER_ACTUATORS: [&str; 6] = ["intvelocity", "damper", "cylinder", "muscle", "adhesion", "plugin"];

/// One actuator's law (see the module documentation).
pub(super) struct ActuatorLaw {
    /// `g`.
    pub gain: f64,
    /// `b₀, b₁, b₂`.
    pub bias: [f64; 3],
    /// The control's range (infinite bounds where not limited).
    pub ctrl_range: [f64; 2],
    /// The force's range, before the gear (infinite bounds where not limited).
    pub force_range: [f64; 2],
    /// `gear`.
    pub gear: f64,
}

impl ActuatorLaw {
    /// True where the force depends on the joint's angle or rate.
    pub fn servo(&self) -> bool {
        self.bias[1] != 0.0 || self.bias[2] != 0.0
    }

    /// A motor's range for its control: the two ranges met (its gain is 1).
    pub fn motor_range(&self) -> [f64; 2] {
        [
            self.ctrl_range[0].max(self.force_range[0]),
            self.ctrl_range[1].min(self.force_range[1]),
        ]
    }
}

impl<'a> Reader<'_, 'a> {
    /// The law of actuator `c`, or a one-line error naming what is outside the subset.
    pub(super) fn actuator_law(&self, c: Node<'a, 'a>) -> Result<ActuatorLaw, SceneError> {
        let tag = c.tag_name().name();
        if !ACTUATORS.contains(&tag) {
            let what = if OTHER_ACTUATORS.contains(&tag) {
                "is outside the subset"
            } else {
                "is not an MJCF actuator"
            };
            return Err(self.err(
                c,
                format!("<actuator> <{tag}> {what} (motor, position, velocity and general with a fixed gain and an affine bias are read)"),
            ));
        }
        self.shared_defaults(c)?;
        let common = [
            "name",
            "joint",
            "gear",
            "class",
            "ctrlrange",
            "ctrllimited",
            "forcerange",
            "forcelimited",
        ];
        let own: &[&str] = match tag {
            "position" => &["kp", "kv", "dampratio", "timeconst", "inheritrange"],
            "velocity" => &["kv"],
            "general" => &["gaintype", "biastype", "dyntype", "gainprm", "biasprm", "dynprm"],
            _ => &[],
        };
        self.attributes(c, &[&common[..], own].concat(), &["group"])?;
        // What would change the force and is not modelled: refused unless at its default.
        for (key, instead) in [
            ("dampratio", "give the damping as kv"),
            ("timeconst", "an activation filter is not modelled"),
            ("inheritrange", "give ctrlrange"),
        ] {
            if tag == "position" && self.number(c, key, 0.0)? != 0.0 {
                return Err(self.err(
                    c,
                    format!("<position> {key} other than 0 is outside the subset ({instead})"),
                ));
            }
        }
        if tag == "general" {
            for (key, read) in [("gaintype", "fixed"), ("dyntype", "none")] {
                let v = self.value(c, key).unwrap_or(read);
                if v != read {
                    return Err(self.err(
                        c,
                        format!("<general> {key}=\"{v}\" is outside the subset ({read} is read)"),
                    ));
                }
            }
        }
        let (gain, bias) = match tag {
            "motor" => (1.0, [0.0; 3]),
            "position" => {
                let (kp, kv) = (self.number(c, "kp", 1.0)?, self.number(c, "kv", 0.0)?);
                (kp, [0.0, -kp, -kv])
            }
            "velocity" => {
                let kv = self.number(c, "kv", 1.0)?;
                (kv, [0.0, 0.0, -kv])
            }
            _ => {
                let gain = self.parameters(c, "gainprm", 1.0)?[0];
                let bias = match self.value(c, "biastype").unwrap_or("none") {
                    "none" => [0.0; 3],
                    "affine" => {
                        let b = self.parameters(c, "biasprm", 0.0)?;
                        [b[0], b[1], b[2]]
                    }
                    other => {
                        return Err(self.err(
                            c,
                            format!("<general> biastype=\"{other}\" is outside the subset (none and affine are read)"),
                        ))
                    }
                };
                (gain, bias)
            }
        };
        for (k, v) in [("kp", gain), ("kv", -bias[2])] {
            if !v.is_finite() {
                return Err(self.err(c, format!("<{tag}>: its {k} is not a finite number")));
            }
        }
        // A constant force with a servo, a pull away from the target and a push along the rate
        // have no law here.
        if bias[0] != 0.0 {
            return Err(self.err(
                c,
                format!("<{tag}>: a constant bias (biasprm's first value) is outside the subset"),
            ));
        }
        if bias[1] > 0.0 || bias[2] > 0.0 {
            return Err(self.err(
                c,
                format!("<{tag}>: a bias that pushes away from the target or along the rate (biasprm above 0) is outside the subset"),
            ));
        }
        let gear = self.numbers::<1>(c, "gear")?.map_or(1.0, |[g]| g);
        if !gear.is_finite() || gear == 0.0 {
            return Err(self.err(c, format!("<{tag}> gear=\"{gear}\" is not a finite non-zero number")));
        }
        let law = ActuatorLaw {
            gain,
            bias,
            ctrl_range: self.range(c, "ctrlrange", "ctrllimited")?,
            force_range: self.range(c, "forcerange", "forcelimited")?,
            gear,
        };
        if tag == "motor" && law.motor_range()[0] > law.motor_range()[1] {
            return Err(self.err(c, "<motor>: ctrlrange and forcerange do not overlap"));
        }
        Ok(law)
    }

    /// MuJoCo keeps one actuator default per class, which every actuator element writes and
    /// reads; this reader keeps them by element. An element whose class also sets the default
    /// of another actuator element would read differently here: refused.
    fn shared_defaults(&self, c: Node<'a, 'a>) -> Result<(), SceneError> {
        let tag = c.tag_name().name();
        let class = c
            .attribute("class")
            .or_else(|| c.ancestors().skip(1).find_map(|a| a.attribute("childclass")));
        for name in class.into_iter().chain(["main"]) {
            let Some(d) = self.defaults.get(name) else {
                continue;
            };
            if let Some(other) = ACTUATORS
                .iter()
                .chain(&OTHER_ACTUATORS)
                .find(|t| **t != tag && d.contains_key(**t))
            {
                return Err(self.err(
                    c,
                    format!("<{tag}> in class '{name}', whose defaults also set <{other}>: MuJoCo shares one actuator default between them, which this reader does not"),
                ));
            }
        }
        Ok(())
    }

    /// `key`'s numbers (MuJoCo reads up to ten), the rest `fill`.
    fn parameters(&self, c: Node<'a, 'a>, key: &str, fill: f64) -> Result<[f64; 10], SceneError> {
        let mut out = [0.0; 10];
        out[0] = fill;
        let Some(s) = self.value(c, key) else {
            return Ok(out);
        };
        out[0] = 0.0;
        let parts: Vec<&str> = s.split_whitespace().collect();
        if parts.len() > 10 {
            return Err(self.err(c, format!("{key} has {} numbers; MuJoCo reads at most 10", parts.len())));
        }
        for (o, p) in out.iter_mut().zip(parts) {
            *o = p
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| self.err(c, format!("{key}: '{p}' is not a finite number")))?;
        }
        Ok(out)
    }

    /// A range that holds where limited ([`Reader::limited_range`]); infinite bounds elsewhere.
    fn range(&self, c: Node<'a, 'a>, key: &str, limited: &str) -> Result<[f64; 2], SceneError> {
        match self.limited_range(c, key, limited)? {
            Some([lo, hi]) if lo.is_nan() || hi.is_nan() || lo > hi => Err(self.err(
                c,
                format!(
                    "<{}> {key}=\"{lo} {hi}\": the first bound is above the second",
                    c.tag_name().name()
                ),
            )),
            Some(bounds) => Ok(bounds),
            None => Ok([f64::NEG_INFINITY, f64::INFINITY]),
        }
    }
}
