//! `dalembert linearize`: [`dalembert::Scene::linearize`] printed, and written as CSV.

use dalembert::output::shortest;
use dalembert::{About, Linearization, LinearizeOptions};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `linearize`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML, URDF or MJCF).
    scene: PathBuf,
    /// Named inputs of the scene (comma-separated): the columns of B and D.
    #[arg(long, value_delimiter = ',')]
    inputs: Vec<String>,
    /// Output columns, as in the CSV of `simulate` (comma-separated): the rows of C and D.
    #[arg(long, value_delimiter = ',')]
    outputs: Vec<String>,
    /// The independent coordinates, by position-state name (`crank.angle`, `slider.x`, `top.rx'`);
    /// default: the scene's `independent`, or coordinate partitioning's choice.
    #[arg(long, value_delimiter = ',')]
    states: Vec<String>,
    /// The operating point: `equilibrium` (the static equilibrium, inputs at 0) or `initial` (the
    /// scene's initial state).
    #[arg(long, default_value = "equilibrium", value_parser = ["equilibrium", "initial"])]
    at: String,
    /// Write the matrices as one CSV: a row per state rate, then per output; columns `row`,
    /// `at` (the value at the operating point), the states (A, C), the inputs (B, D). A name
    /// ending in `.npz` writes NumPy's archive instead (`numpy.load`): arrays `A`, `B`, `C`, `D`,
    /// `drift`, `at` (the outputs at the operating point), `t`, and `states`, `inputs`,
    /// `outputs` (strings).
    #[arg(long)]
    output: Option<PathBuf>,
}

/// `dalembert linearize SCENE`.
pub fn linearize(a: Args) -> Result<(), String> {
    let scene = crate::paths::load_scene(&a.scene)?;
    let about = if a.at == "initial" {
        About::Initial
    } else {
        About::Equilibrium
    };
    let options = LinearizeOptions {
        inputs: a.inputs,
        outputs: a.outputs,
        states: a.states,
        about,
    };
    let lin = scene.linearize(&options).map_err(|e| e.to_string())?;
    outln!("scene        {}", scene.name);
    outln!(
        "linearized   about the {} at t = {}: {} state(s), {} input(s), {} output(s)",
        if a.at == "initial" {
            "initial state"
        } else {
            "static equilibrium"
        },
        shortest(lin.t),
        lin.states.len(),
        lin.inputs.len(),
        lin.outputs.len()
    );
    outln!("states       {}", lin.states.join(", "));
    let rates: Vec<String> = lin.states.iter().map(|s| format!("d({s})/dt")).collect();
    outln!("\nA (state rates over states)");
    table(&rates, &lin.states, |i, j| lin.a[(i, j)]);
    if !lin.inputs.is_empty() {
        outln!("\nB (state rates over inputs)");
        table(&rates, &lin.inputs, |i, j| lin.b[(i, j)]);
    }
    if !lin.outputs.is_empty() {
        outln!("\nC (outputs over states)");
        table(&lin.outputs, &lin.states, |i, j| lin.c[(i, j)]);
        if !lin.inputs.is_empty() {
            outln!("\nD (outputs over inputs)");
            table(&lin.outputs, &lin.inputs, |i, j| lin.d[(i, j)]);
        }
    }
    if lin.drift.iter().any(|&x| x != 0.0) && a.at == "initial" {
        outln!(
            "\nat the operating point the state moves: {}",
            pairs(&rates, &lin.drift)
        );
    }
    if let Some(path) = &a.output {
        let npz = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npz"));
        match npz {
            true => write_npz(path, &lin),
            false => write_csv(path, &lin),
        }
        .map_err(|e| format!("{}: {e}", path.display()))?;
        outln!("\nwritten      {}", path.display());
    }
    Ok(())
}

fn pairs(names: &[String], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(n, v)| format!("{n} = {}", shortest(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A labelled matrix, columns padded to their widest entry.
fn table(rows: &[String], columns: &[String], value: impl Fn(usize, usize) -> f64) {
    let cell = |x: f64| format!("{x:.6e}");
    let label = rows.iter().map(String::len).max().unwrap_or(0);
    let widths: Vec<usize> = columns
        .iter()
        .enumerate()
        .map(|(j, c)| {
            (0..rows.len())
                .map(|i| cell(value(i, j)).len())
                .max()
                .unwrap_or(0)
                .max(c.len())
        })
        .collect();
    let header: Vec<String> = columns.iter().zip(&widths).map(|(c, w)| format!("{c:>w$}")).collect();
    outln!("{:label$}  {}", "", header.join("  "));
    for (i, r) in rows.iter().enumerate() {
        let line: Vec<String> = (0..columns.len())
            .map(|j| format!("{:>w$}", cell(value(i, j)), w = widths[j]))
            .collect();
        outln!("{r:label$}  {}", line.join("  "));
    }
}

/// The linear model as NumPy's `.npz` archive ([`crate::npz`]).
fn write_npz(path: &PathBuf, lin: &Linearization) -> std::io::Result<()> {
    use crate::npz::Array;
    // NumPy's arrays here are in C order (by rows).
    let by_rows = |(r, c): (usize, usize), at: &dyn Fn(usize, usize) -> f64| {
        Array::Numbers((0..r).flat_map(|i| (0..c).map(move |j| at(i, j))).collect(), vec![r, c])
    };
    let vector = |v: &[f64]| Array::Numbers(v.to_vec(), vec![v.len()]);
    let bytes = crate::npz::archive(&[
        ("A", by_rows(lin.a.shape(), &|i, j| lin.a[(i, j)])),
        ("B", by_rows(lin.b.shape(), &|i, j| lin.b[(i, j)])),
        ("C", by_rows(lin.c.shape(), &|i, j| lin.c[(i, j)])),
        ("D", by_rows(lin.d.shape(), &|i, j| lin.d[(i, j)])),
        ("drift", vector(&lin.drift)),
        ("at", vector(&lin.outputs_at)),
        ("t", Array::Numbers(vec![lin.t], Vec::new())),
        ("states", Array::Strings(&lin.states)),
        ("inputs", Array::Strings(&lin.inputs)),
        ("outputs", Array::Strings(&lin.outputs)),
    ]);
    std::fs::write(path, bytes)
}

/// The matrices `[A B; C D]` with row names and the operating point's values (`at`).
fn write_csv(path: &PathBuf, lin: &Linearization) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    let header: Vec<&str> = ["row", "at"]
        .into_iter()
        .chain(lin.states.iter().map(String::as_str))
        .chain(lin.inputs.iter().map(String::as_str))
        .collect();
    writeln!(out, "{}", header.join(","))?;
    let n = lin.states.len();
    for i in 0..n {
        let values = std::iter::once(lin.drift[i])
            .chain((0..n).map(|j| lin.a[(i, j)]))
            .chain((0..lin.inputs.len()).map(|j| lin.b[(i, j)]));
        let cells: Vec<String> = values.map(shortest).collect();
        writeln!(out, "d({})/dt,{}", lin.states[i], cells.join(","))?;
    }
    for (i, name) in lin.outputs.iter().enumerate() {
        let values = std::iter::once(lin.outputs_at[i])
            .chain((0..n).map(|j| lin.c[(i, j)]))
            .chain((0..lin.inputs.len()).map(|j| lin.d[(i, j)]));
        let cells: Vec<String> = values.map(shortest).collect();
        writeln!(out, "{name},{}", cells.join(","))?;
    }
    out.flush()
}
