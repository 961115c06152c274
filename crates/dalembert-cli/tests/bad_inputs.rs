//! The bad-input suite: every file in `tests/bad_inputs/` is a scene (or a valid scene with bad
//! command-line arguments) that must end with exactly one line on stderr, the message in its
//! `# expect:` line, and a non-zero exit: never a panic, never a silent success.
//!
//! File format: line 1 `# expect: MESSAGE` (`{file}` stands for the file's path), line 2
//! `# args: check` or `# args: simulate FLAGS…`, then the scene. A URDF or MJCF case (`.urdf`, `.xml`) writes
//! the two lines as XML comments: `<!-- expect: MESSAGE -->`, `<!-- args: check -->`.

use std::process::Command;

#[test]
fn every_bad_input_gets_its_one_line_error() {
    let dir = format!("{}/../../tests/bad_inputs", env!("CARGO_MANIFEST_DIR"));
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "urdf" || e == "xml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 100, "{} cases", paths.len());
    let mut failures = Vec::new();
    for path in &paths {
        let bytes = std::fs::read(path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        let mut lines = text.lines();
        let header = |line: Option<&str>, key: &str| -> Option<String> {
            let line = line?;
            let hash = line.strip_prefix(&format!("# {key}: "));
            let xml = line
                .strip_prefix(&format!("<!-- {key}: "))
                .and_then(|l| l.strip_suffix(" -->"));
            hash.or(xml).map(String::from)
        };
        let expect = header(lines.next(), "expect").expect("an expect: line");
        let args_line = header(lines.next(), "args").expect("an args: line");
        let args: Vec<&str> = args_line.split_whitespace().collect();
        let file = path.to_str().unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_dalembert"))
            .arg(args[0])
            .arg(file)
            .args(&args[1..])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let expected = format!("error: {}\n", expect.replace("{file}", file));
        // A code of 1 or 2: the program reported the error itself (a panic exits with 101, a
        // signal with none).
        let clean_exit = matches!(out.status.code(), Some(1) | Some(2));
        if !clean_exit || err != expected {
            failures.push(format!(
                "{}: exit {:?}\n  got:      {}\n  expected: {}",
                path.file_name().unwrap().to_string_lossy(),
                out.status.code(),
                err.trim_end(),
                expected.trim_end()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        paths.len(),
        failures.join("\n")
    );
}
