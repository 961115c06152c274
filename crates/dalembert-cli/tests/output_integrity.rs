//! A run that stops for any reason leaves a well-formed CSV holding every row computed so far:
//! a closed stdout pipe, SIGINT and SIGTERM; names that need quoting round-trip through `plot`.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

mod common;
use common::{scene, tmp};

/// Rows of a CSV file, failing on any row whose field count differs from the header's (RFC 4180
/// parsing: a cut last row is caught).
fn rows(path: &std::path::Path) -> Vec<csv::StringRecord> {
    let mut rdr = csv::Reader::from_path(path).unwrap();
    let n = rdr.headers().unwrap().len();
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.expect("well-formed row")).collect();
    assert!(rows.iter().all(|r| r.len() == n));
    rows
}

#[test]
fn a_closed_stdout_pipe_still_completes_the_csv() {
    let csv = tmp("piped.csv");
    let mut child = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args(["simulate", &scene("chain-8.toml"), "--end", "20", "--output"])
        .arg(&csv)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read the first line, then close the pipe (as `| head -1` does).
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.starts_with("scene"), "{first}");
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows = rows(&csv);
    // Every output time of the run: t = 0, 0.01, …, 20.
    assert_eq!(rows.len(), 2001);
    assert_eq!(&rows[2000][0], "20");
}

fn interrupt(signal: &str, every: &str) {
    let csv = tmp(&format!("{signal}-{every}.csv"));
    let child = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "simulate",
            &scene("chain-8.toml"),
            "--end",
            "1e5",
            "--every",
            every,
            "--output",
        ])
        .arg(&csv)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(700));
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    // One error line; before it the warning that 1e8 steps take minutes.
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.iter().filter(|l| l.starts_with("error: ")).count(), 1, "{err}");
    assert!(
        lines[..lines.len() - 1]
            .iter()
            .all(|l| l.starts_with("warning: a step of 1e-3 s over 1e5 s is 1e8 steps")),
        "{err}"
    );
    let rows = rows(&csv);
    let expected = format!(
        "interrupted; {} holds the {} rows up to t = {}",
        csv.display(),
        rows.len(),
        &rows[rows.len() - 1][0]
    );
    assert!(err.contains(&expected), "{err}\nexpected: {expected}");
}

#[test]
fn sigint_finishes_the_row_and_flushes() {
    interrupt("INT", "0.01");
}

#[test]
fn sigterm_with_sparse_output_keeps_the_rows_so_far() {
    // One row per 1000 s of simulated time: only the row at t = 0 exists when the signal comes;
    // it must be on disk (it was a 0-byte file before).
    interrupt("TERM", "1000");
}

#[test]
fn names_that_need_quoting_round_trip_through_the_csv_and_plot() {
    let text = std::fs::read_to_string(scene("pendulum.toml"))
        .unwrap()
        .replace("name = \"rod\"", "name = \"rod,evil \\\"quoted\\\"\"")
        .replace("[\"ground\", \"rod\"]", "[\"ground\", \"rod,evil \\\"quoted\\\"\"]");
    let path = tmp("evil.toml");
    std::fs::write(&path, text).unwrap();
    let csv = tmp("evil.csv");
    let status = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "simulate",
            path.to_str().unwrap(),
            "--end",
            "0.1",
            "--output",
            csv.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    let mut rdr = csv::Reader::from_path(&csv).unwrap();
    let header = rdr.headers().unwrap().clone();
    assert_eq!(&header[1], "rod,evil \"quoted\".x");
    assert_eq!(header.len(), 12, "t, 6 body columns, pivot fx fy, 3 monitors");
    assert_eq!(rows(&csv).len(), 11);
    // `animate --from` finds the body's columns by their exact names.
    let page = tmp("evil.html");
    let out = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "animate",
            path.to_str().unwrap(),
            "--from",
            csv.to_str().unwrap(),
            "--output",
            page.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn tiny_numbers_are_written_short_and_read_back_exactly() {
    let mut out = Vec::new();
    for x in [1e-300, -2.5e-7, 0.0, 1.5, 123456.789, 3e20, f64::MIN_POSITIVE] {
        out.clear();
        dalembert::output::write_number(&mut out, x).unwrap();
        let s = String::from_utf8(out.clone()).unwrap();
        assert!(s.len() <= 24, "{s}");
        assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
    }
}

/// Starts `dalembert sweep` on the chain of eight with `set`, writing `csv`.
fn start_sweep(csv: &std::path::Path, set: &str) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "sweep",
            &scene("chain-8.toml"),
            "--set",
            set,
            "--threads",
            "2",
            "--output",
        ])
        .arg(csv)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until `csv` holds `rows` rows besides its header (at most 60 s).
fn wait_for_rows(csv: &std::path::Path, rows: usize) {
    for _ in 0..600 {
        let n = std::fs::read_to_string(csv).map_or(0, |t| t.lines().count());
        if n > rows {
            return;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    panic!("{} never held {rows} rows", csv.display());
}

fn signal(child: &std::process::Child, signal: &str) {
    let sent = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
}

/// SIGINT and SIGTERM stop a sweep's runs in progress at their next step (within a second, where
/// each run alone would take hours), exit 130, and leave the header, the finished run's row and
/// one row per stopped run marked "interrupted at t = …" or "cancelled". The first run (end
/// 0.05 s) finishes at once: its row is there with its numbers.
fn interrupt_sweep(sig: &str) {
    let csv = tmp(&format!("sweep-{sig}.csv"));
    let child = start_sweep(&csv, "simulation.end=0.05,1e5,1e5,1e5");
    wait_for_rows(&csv, 1);
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, sig);
    let sent = std::time::Instant::now();
    let out = child.wait_with_output().unwrap();
    let stopped_in = sent.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(
        stopped_in < Duration::from_secs(1),
        "stopped {stopped_in:?} after the signal"
    );
    let rows = rows(&csv);
    assert_eq!(rows.len(), 4, "one row per run");
    let error = |r: &csv::StringRecord| r[r.len() - 1].to_string();
    let finished: Vec<_> = rows.iter().filter(|r| error(r).is_empty()).collect();
    assert_eq!(finished.len(), 1, "{rows:?}");
    assert_eq!(&finished[0][0], "0.05");
    assert!(finished[0][1].parse::<f64>().unwrap().is_finite());
    let marks: Vec<String> = rows.iter().map(error).filter(|e| !e.is_empty()).collect();
    assert!(
        marks
            .iter()
            .all(|e| e.starts_with("interrupted at t = ") || e == "cancelled"),
        "{marks:?}"
    );
    assert!(marks.iter().any(|e| e.starts_with("interrupted at t = ")), "{marks:?}");
    assert!(err.contains("error: interrupted: 1 runs finished"), "{err}");
}

#[test]
fn sigint_stops_a_sweep_within_a_second_keeping_every_row() {
    interrupt_sweep("INT");
}

#[test]
fn sigterm_stops_a_sweep_within_a_second_keeping_every_row() {
    interrupt_sweep("TERM");
}

/// The sweep's CSV is streamed: after SIGKILL (no chance to write anything more) the file holds
/// the header and the row of the run that had finished.
#[test]
fn a_killed_sweep_leaves_its_finished_rows() {
    let csv = tmp("sweep-KILL.csv");
    let mut child = start_sweep(&csv, "simulation.end=0.05,1e5");
    wait_for_rows(&csv, 1);
    child.kill().unwrap();
    child.wait().unwrap();
    let rows = rows(&csv);
    assert_eq!(rows.len(), 1);
    assert_eq!(&rows[0][0], "0.05");
    assert_eq!(&rows[0][rows[0].len() - 1], "");
}

/// SIGINT stops `trade` in the run in progress: exit 130, and trade.csv holds the runs made, the
/// last one marked interrupted.
#[test]
fn sigint_stops_a_trade_keeping_the_runs_made() {
    let dir = tmp("trade-INT");
    let child = Command::new(env!("CARGO_BIN_EXE_dalembert"))
        .args([
            "trade",
            &scene("chain-8.toml"),
            "--formulations",
            "augmented",
            "--integrators",
            "rk4",
            "--stabilizations",
            "projection",
            "--steps",
            "1e-3,1e-7",
            "--end",
            "1",
            "--output",
        ])
        .arg(&dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The reference (dopri5 at 1e-12) and the run at 1e-3 take about 0.1 s; the one at 1e-7,
    // 1e7 steps, minutes.
    std::thread::sleep(Duration::from_secs(3));
    signal(&child, "INT");
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    let text = std::fs::read_to_string(dir.join("trade.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[1].ends_with(",ok"), "{text}");
    assert!(lines[2].contains("interrupted at t = "), "{text}");
}
