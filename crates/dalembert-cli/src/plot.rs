//! `dalembert plot`: columns of a result CSV against time, as SVG.

use plotters::prelude::*;
use std::path::PathBuf;

/// Arguments of `plot`.
#[derive(clap::Args)]
pub struct Args {
    /// CSV written by `simulate` or `inverse`.
    csv: PathBuf,
    /// Comma-separated column names to plot against `t`.
    #[arg(long, value_delimiter = ',', required = true)]
    columns: Vec<String>,
    /// SVG file to write.
    #[arg(long)]
    output: PathBuf,
}

pub fn run(a: Args) -> Result<(), String> {
    let file = std::fs::File::open(&a.csv).map_err(|e| format!("{}: {e}", a.csv.display()))?;
    let table =
        dalembert::output::read_columns(std::io::BufReader::new(file), &a.csv.display().to_string(), &a.columns)
            .map_err(|e| e.to_string())?;
    let k = a.columns.len();
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
    let pad = ((y1 - y0) * 0.05).max(1e-12);
    let root = SVGBackend::new(&a.output, (900, 540)).into_drawing_area();
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
    for (i, (s, name)) in series.into_iter().zip(&a.columns).enumerate() {
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
    outln!("wrote {}", a.output.display());
    Ok(())
}
