//! The methods' parameters as command-line flags (`--rtol`, `--rho-inf`), one per key of the
//! integrators' registry: a method registered with a new parameter gets its flag here without a
//! change to the command line.

use clap::{Arg, ArgMatches, Args, Command, FromArgMatches};
use dalembert::integrators::METHODS;

/// The values given for the registry's parameters, by key.
#[derive(Debug, Clone, Default)]
pub struct MethodParams(pub Vec<(String, f64)>);

/// Every parameter once (two methods may share a key), with the methods that have it.
fn parameters() -> Vec<(&'static str, &'static str, Vec<&'static str>)> {
    let mut out: Vec<(&'static str, &'static str, Vec<&'static str>)> = Vec::new();
    for e in METHODS {
        for p in e.parameters {
            match out.iter_mut().find(|(k, _, _)| *k == p.key) {
                Some((_, _, users)) => users.push(e.name),
                None => out.push((p.key, p.doc, vec![e.name])),
            }
        }
    }
    out
}

impl Args for MethodParams {
    fn augment_args(mut cmd: Command) -> Command {
        for (key, doc, users) in parameters() {
            // Numbers may be negative on the command line, so that the rule rejecting them speaks.
            cmd = cmd.arg(
                Arg::new(key)
                    .long(key.replace('_', "-"))
                    .value_name(key.to_uppercase())
                    .value_parser(clap::value_parser!(f64))
                    .allow_hyphen_values(true)
                    .help(format!("{doc} ({})", users.join(", "))),
            );
        }
        cmd
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}

impl FromArgMatches for MethodParams {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut out = MethodParams::default();
        out.update_from_arg_matches(m)?;
        Ok(out)
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        for (key, _, _) in parameters() {
            if let Some(v) = m.get_one::<f64>(key) {
                self.0.retain(|(k, _)| k != key);
                self.0.push((key.to_string(), *v));
            }
        }
        Ok(())
    }
}
