//! Named inputs on the command line: `check` lists them; a run from start to end holds them at 0.

mod common;
use common::{dalembert, tmp};

/// A slider on a guide pushed by input `push`, and a torque input on nothing else.
const PUSHED: &str = r#"
[[bodies]]
name = "slider"
mass = 2.0
inertia = 0.1
position = [0.0, 0.0]
[[joints]]
name = "guide"
type = "prismatic"
bodies = ["ground", "slider"]
at = [0.0, 0.0]
axis = [1.0, 0.0]
[[forces]]
name = "push"
type = "force"
body = "slider"
fx = { input = "push" }
fy = { input = "lift" }
[simulation]
end = 0.5
"#;

#[test]
fn check_lists_the_inputs_and_a_run_holds_them_at_zero() {
    let path = tmp("pushed.toml");
    std::fs::write(&path, PUSHED).unwrap();
    let p = path.to_str().unwrap();
    let (ok, out, err) = dalembert(&["check", p]);
    assert!(ok, "{err}");
    assert!(
        out.lines().any(|l| l.starts_with("inputs       push, lift (held")),
        "{out}"
    );
    // No force acts in a run from start to end: the slider stays where it is, exactly.
    let csv = tmp("pushed.csv");
    let (ok, _, err) = dalembert(&["simulate", p, "--output", csv.to_str().unwrap()]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let x = header.iter().position(|c| *c == "slider.x").unwrap();
    let last: Vec<&str> = text.lines().last().unwrap().split(',').collect();
    assert_eq!(last[0].parse::<f64>().unwrap(), 0.5);
    assert_eq!(last[x].parse::<f64>().unwrap(), 0.0);
}
