//! The `dalembert` command. See `dalembert --help` and `docs/scenes.md`.

/// `println!` that ends the program quietly when stdout is closed (e.g. piped into `head`).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            $crate::stdout_failed(e);
        }
    }};
}

/// `print!` with the same behaviour as [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($arg)*) {
            $crate::stdout_failed(e);
        }
    }};
}

/// A closed pipe (`| head`) silences the summary but the run goes on, so that files being written
/// are completed; any other write error on stdout is reported once and the work goes on likewise.
fn stdout_failed(e: std::io::Error) {
    use std::sync::atomic::{AtomicBool, Ordering};
    static REPORTED: AtomicBool = AtomicBool::new(false);
    if e.kind() != std::io::ErrorKind::BrokenPipe && !REPORTED.swap(true, Ordering::Relaxed) {
        eprintln!("error: writing to stdout: {e}");
    }
}

/// The flag set by SIGINT and SIGTERM: runs stop after the current step, finish the row they are
/// writing and flush their output. (A second signal does not end the program at once: `timeout`
/// and process groups can deliver one interrupt twice, which would cut the row being written.
/// The flag is read after every step, so the stop comes within one step; Ctrl-\ still quits.)
pub fn interrupt_flag() -> &'static std::sync::Arc<std::sync::atomic::AtomicBool> {
    use std::sync::{atomic::AtomicBool, Arc, OnceLock};
    static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            // Registration fails only for forbidden signals (not these); without it a signal
            // keeps its default action, as before.
            let _ = signal_hook::flag::register(sig, Arc::clone(&flag));
        }
        flag
    })
}

mod animate;
mod check;
mod inverse;
mod linearize;
mod method_args;
mod npz;
mod paths;
mod plot;
mod simulate;
mod statics;
mod sweep;
mod trade;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Constrained multibody dynamics, planar and spatial, from scene files.
#[derive(Parser)]
#[command(name = "dalembert", version, about, arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and print a summary (and write a CSV with --output).
    Simulate(simulate::Args),
    /// Parse and assemble a scene; report degrees of freedom, redundancy, initial accelerations and reactions.
    Check(check::Args),
    /// Inverse dynamics of a fully driven scene: driver efforts and reactions over time.
    Inverse(inverse::Args),
    /// Plot columns of a result CSV against time as an SVG.
    Plot(plot::Args),
    /// Measure the speed–accuracy trade over formulations, integrators, treatments and steps.
    Trade(trade::Args),
    /// Run a scene for every combination of parameter values, in parallel (--set path=v1,v2).
    Sweep(sweep::Args),
    /// Write a self-contained HTML animation of a scene's motion (or of a saved run, --from).
    Animate(animate::Args),
    /// The static equilibrium nearest the scene's position: positions, reactions, stability.
    Equilibrium(statics::EquilibriumArgs),
    /// Natural frequencies, damping ratios and mode shapes about the static equilibrium.
    Modes(statics::ModesArgs),
    /// The linear model (A, B, C, D) in minimal coordinates about the equilibrium or the initial state.
    Linearize(linearize::Args),
}

/// A usage error on one line that names what is wrong: the missing arguments, the suggestion for
/// a mistyped command or flag, the usage, and the commands when the command itself is wrong.
fn usage_error(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ErrorKind};
    use clap::CommandFactory;
    let text = e.to_string();
    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        // Plain `dalembert`: the help, which lists the commands.
        return text.trim_end().to_string();
    }
    if e.kind() == ErrorKind::InvalidSubcommand {
        let names: Vec<String> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .filter(|n| n != "help")
            .collect();
        let given = e
            .get(ContextKind::InvalidSubcommand)
            .map(|v| v.to_string())
            .unwrap_or_default();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let hint = dalembert::scene::nearest(&given, &refs).map_or(String::new(), |n| format!("; did you mean '{n}'?"));
        return format!(
            "error: unknown command '{given}'{hint} (commands: {}; see --help)",
            names.join(", ")
        );
    }
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut out = lines
        .next()
        .unwrap_or("error: invalid arguments")
        .trim_end_matches(':')
        .to_string();
    let mut listed = Vec::new();
    for line in lines {
        if let Some(tip) = line.strip_prefix("tip: ") {
            out.push_str(&format!("; {tip}"));
        } else if let Some(usage) = line.strip_prefix("Usage: ") {
            out.push_str(&format!("; usage: {usage}"));
        } else if line.starts_with("For more information") {
        } else {
            listed.push(line);
        }
    }
    if !listed.is_empty() {
        // The missing arguments, listed under the first line.
        let (head, rest) = out.split_once("; ").map_or((out.as_str(), ""), |(h, r)| (h, r));
        out = format!(
            "{head}: {}{}{rest}",
            listed.join(", "),
            if rest.is_empty() { "" } else { "; " }
        );
    }
    format!("{out} (see --help)")
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Usage errors in one line, like every other error; help and version print as usual.
        Err(e) if e.use_stderr() => {
            eprintln!("{}", usage_error(&e));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Check(a) => check::run(a),
        Command::Equilibrium(a) => statics::equilibrium(a),
        Command::Modes(a) => statics::modes(a),
        Command::Linearize(a) => linearize::linearize(a),
        Command::Inverse(a) => inverse::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Trade(a) => trade::run(a),
        Command::Animate(a) => animate::run(a),
        Command::Sweep(a) => sweep::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Every message on one line, whatever user text it quotes.
            eprintln!("error: {}", dalembert::scene::one_line(&e));
            if interrupt_flag().load(std::sync::atomic::Ordering::Relaxed) {
                ExitCode::from(130) // 128 + SIGINT, as shells report an interrupted command
            } else {
                ExitCode::FAILURE
            }
        }
    }
}
