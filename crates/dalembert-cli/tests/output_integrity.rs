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
    assert_eq!(err.lines().count(), 1, "{err}");
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
