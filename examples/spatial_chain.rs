//! Writes the spatial chain of `shared/anchors` (`chain3d`) with N links as a scene file.
//!
//! ```text
//! cargo run --release --example spatial_chain -- 16 > chain3d-16.toml
//! cargo run --release -- simulate chain3d-16.toml
//! ```
//!
//! Arguments: `N` (default 8) and the end time in seconds (default 10).

fn main() {
    let mut args = std::env::args().skip(1);
    let parse = |a: Option<String>, default: f64, what: &str| -> f64 {
        a.map_or(Ok(default), |s| s.parse::<f64>().map_err(|_| s))
            .unwrap_or_else(|s| {
                eprintln!("error: {what} must be a number, got '{s}'");
                std::process::exit(2)
            })
    };
    let n = parse(args.next(), 8.0, "N");
    let end = parse(args.next(), 10.0, "the end time");
    let whole = n >= 1.0 && n.fract() == 0.0 && n <= 100_000.0;
    if !(whole && end.is_finite() && end > 0.0) {
        eprintln!("error: N must be a whole number from 1 to 100000 and the end time positive, got {n} and {end}");
        std::process::exit(2);
    }
    print!("{}", dalembert_testkit::spatial::chain3d_toml(n as usize, end));
}
