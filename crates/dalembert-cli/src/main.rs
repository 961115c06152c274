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
mod method_args;
mod plot;
mod simulate;
mod sweep;
mod trade;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Constrained planar multibody dynamics from scene files.
#[derive(Parser)]
#[command(name = "dalembert", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and print a summary (and write a CSV with --output).
    Simulate(simulate::Args),
    /// Parse and assemble a scene; report degrees of freedom, redundancy, initial accelerations and reactions.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
    },
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
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // Usage errors in one line, like every other error; help and version print as usual.
        Err(e) if e.use_stderr() => {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("error: invalid arguments");
            eprintln!("{first} (see --help)");
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Check { scene } => check::run(&scene),
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
