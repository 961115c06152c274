//! Named inputs on the command line: `check` lists them; a run from start to end holds them at 0.

mod common;
use common::{dalembert, tmp};

#[test]
fn check_lists_the_inputs_and_a_run_holds_them_at_zero() {
    // tests/data/pushed-slider.toml with a second input.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/pushed-slider.toml"
    ))
    .unwrap()
    .replace(
        "fx = { input = \"push\" }",
        "fx = { input = \"push\" }\nfy = { input = \"lift\" }",
    );
    assert!(text.contains("lift"));
    let path = tmp("pushed.toml");
    std::fs::write(&path, text).unwrap();
    let p = path.to_str().unwrap();
    let (ok, out, err) = dalembert(&["check", p]);
    assert!(ok, "{err}");
    assert!(
        out.lines().any(|l| l.starts_with("inputs       push, lift (held")),
        "{out}"
    );
    // No force acts in a run from start to end: the slider stays where it is, exactly.
    let csv = tmp("pushed.csv");
    let (ok, _, err) = dalembert(&["simulate", p, "--end", "0.5", "--output", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let x = header.iter().position(|c| *c == "slider.x").unwrap();
    let last: Vec<&str> = text.lines().last().unwrap().split(',').collect();
    assert_eq!(last[0].parse::<f64>().unwrap(), 0.5);
    assert_eq!(last[x].parse::<f64>().unwrap(), 0.0);
}
