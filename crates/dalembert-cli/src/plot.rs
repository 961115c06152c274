//! `dalembert plot`: columns of a result CSV against time, as SVG.

use plotters::prelude::*;
use std::path::PathBuf;

/// Arguments of `plot`.
#[derive(clap::Args)]
pub struct Args {
    /// CSV written by `simulate` or `inverse`.
    csv: PathBuf,
    /// Column names to plot against `t`, comma-separated or repeated (`--columns a,b --columns c`);
    /// a name that itself contains a comma is taken whole.
    #[arg(long, required = true, num_args = 1..)]
    columns: Vec<String>,
    /// SVG file to write.
    #[arg(long)]
    output: PathBuf,
}

pub fn run(a: Args) -> Result<(), String> {
    crate::paths::refuse_overwriting(&a.output, &[&a.csv])?;
    let origin = a.csv.display().to_string();
    let open = || std::fs::File::open(&a.csv).map_err(|e| format!("{origin}: {e}"));
    let header =
        dalembert::output::read_header(std::io::BufReader::new(open()?), &origin).map_err(|e| e.to_string())?;
    let mut columns = Vec::new();
    for arg in &a.columns {
        columns.extend(split_columns(arg, &header).map_err(|m| format!("{origin}:1: {m}"))?);
    }
    let table = dalembert::output::read_columns(std::io::BufReader::new(open()?), &origin, &columns)
        .map_err(|e| e.to_string())?;
    let k = columns.len();
    let series: Vec<Vec<(f64, f64)>> = (0..k)
        .map(|j| {
            table
                .times
                .iter()
                .enumerate()
                .map(|(i, &t)| (t, table.values[i * k + j]))
                .collect()
        })
        .collect();
    let all = series.iter().flatten();
    let (t0, t1) = all
        .clone()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (y0, y1) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.1), b.max(p.1)));
    if !(t0.is_finite() && y0.is_finite()) {
        return Err("nothing to plot".into());
    }
    let out = a.output.display().to_string();
    draw(&a.output, series, &columns, (t0, t1, y0, y1)).map_err(|e| format!("{out}: {}", plain(&e)))?;
    outln!("wrote {out}");
    Ok(())
}

/// The cause of a drawing error without the plotting library's wrapping ("backend error: Drawing
/// backend error: …").
fn plain(e: &str) -> &str {
    e.rsplit(": ").next().unwrap_or(e)
}

/// Draws `series` named `columns` in the box `(t0, t1, y0, y1)` into the SVG file `output`.
fn draw(
    output: &std::path::Path,
    series: Vec<Vec<(f64, f64)>>,
    columns: &[String],
    (t0, t1, y0, y1): (f64, f64, f64, f64),
) -> Result<(), String> {
    // The SVG is drawn in memory and written at the end, so that a write error names the file.
    let mut svg = String::new();
    {
        let pad = ((y1 - y0) * 0.05).max(1e-12);
        let root = SVGBackend::with_string(&mut svg, (900, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(t0..t1.max(t0 + 1e-12), (y0 - pad)..(y1 + pad))
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("t [s]")
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, (s, name)) in series.into_iter().zip(columns).enumerate() {
            let color = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(s, color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    std::fs::write(output, svg).map_err(|e| e.to_string())
}

/// The column names in one `--columns` argument: split at commas, except where the pieces joined
/// with their commas name a column of `header` (the longest such run is taken), so that a name
/// containing a comma plots as it was written.
fn split_columns(arg: &str, header: &[String]) -> Result<Vec<String>, String> {
    if header.iter().any(|h| h == arg) {
        return Ok(vec![arg.to_string()]);
    }
    let pieces: Vec<&str> = arg.split(',').collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < pieces.len() {
        let longest = (i + 1..=pieces.len())
            .rev()
            .find(|&j| header.iter().any(|h| *h == pieces[i..j].join(",")));
        match longest {
            Some(j) => {
                out.push(pieces[i..j].join(","));
                i = j;
            }
            None => {
                let names: Vec<&str> = header.iter().map(String::as_str).collect();
                return Err(dalembert::output::no_column(pieces[i], &names));
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::split_columns;

    #[test]
    fn names_with_commas_are_taken_whole() {
        let header: Vec<String> = ["t", "a", "b", "f(x,y)", "g,h"].map(String::from).to_vec();
        assert_eq!(split_columns("a,b", &header).unwrap(), ["a", "b"]);
        assert_eq!(split_columns("f(x,y)", &header).unwrap(), ["f(x,y)"]);
        assert_eq!(split_columns("a,g,h,b", &header).unwrap(), ["a", "g,h", "b"]);
        let e = split_columns("a,nosuch", &header).unwrap_err();
        assert!(
            e.starts_with("no column 'nosuch' (its columns: t, a, b, f(x,y), g,h)"),
            "{e}"
        );
    }
}
