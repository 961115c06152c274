//! The motion to play: poses of every body at a sequence of times, from a run or from a result CSV.

use super::Drawing;
use std::io::Read;

/// Poses `[x, y, angle]` of every body at increasing times.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Frames {
    /// Times (s), increasing.
    pub times: Vec<f64>,
    /// Poses, frame after frame: `3 × bodies` numbers per frame.
    pub poses: Vec<f64>,
    /// Number of bodies.
    pub bodies: usize,
}

/// A result CSV that cannot be replayed on a scene. `Display` is one line naming the file, the
/// line and the column at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct FramesError {
    /// The file (or origin) name.
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<u64>,
    /// What is wrong.
    pub message: String,
}

impl Frames {
    /// No frames yet, for `bodies` bodies.
    pub fn new(bodies: usize) -> Self {
        Frames {
            bodies,
            ..Frames::default()
        }
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// True when there is no frame.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// Appends the frame at `t` from the system positions `q` (`[x, y, θ]` per body).
    pub fn push(&mut self, t: f64, q: &[f64]) {
        debug_assert_eq!(q.len(), 3 * self.bodies);
        self.times.push(t);
        self.poses.extend_from_slice(q);
    }

    /// At most `max` frames (at least two), evenly spread over the run and always keeping the first
    /// and the last: a screen shows no more than its refresh rate, so a long, finely sampled run is
    /// thinned to what can be seen.
    pub fn decimated(&self, max: usize) -> Frames {
        let n = self.len();
        let max = max.max(2);
        if n <= max {
            return self.clone();
        }
        let mut out = Frames::new(self.bodies);
        let w = 3 * self.bodies;
        for i in 0..max {
            let k = ((i as f64) * (n - 1) as f64 / (max - 1) as f64).round() as usize;
            out.push(self.times[k], &self.poses[k * w..(k + 1) * w]);
        }
        out
    }

    /// Reads the frames of `drawing`'s bodies from a result CSV written by `simulate` (columns `t`
    /// and `<body>.x`, `.y`, `.angle`; other columns are ignored). `origin` names the file in
    /// errors: a missing column, a field that is not a finite number, times that do not increase.
    pub fn from_csv(reader: impl Read, drawing: &Drawing, origin: &str) -> Result<Frames, FramesError> {
        let err = |line: Option<u64>, message: String| FramesError {
            file: origin.to_string(),
            line,
            message,
        };
        let mut rdr = csv::ReaderBuilder::new().has_headers(true).from_reader(reader);
        let header = rdr
            .headers()
            .map_err(|e| err(Some(1), format!("not a result CSV: {e}")))?
            .clone();
        let column = |name: &str| -> Result<usize, FramesError> {
            header.iter().position(|h| h == name).ok_or_else(|| {
                err(
                    Some(1),
                    format!(
                        "does not match the scene: no column '{name}' (write it with `dalembert simulate --output`)"
                    ),
                )
            })
        };
        let t_col = column("t")?;
        let mut cols = Vec::with_capacity(3 * drawing.bodies.len());
        for b in &drawing.bodies {
            for c in ["x", "y", "angle"] {
                let name = format!("{}.{c}", b.name);
                cols.push((column(&name)?, name));
            }
        }
        let mut frames = Frames::new(drawing.bodies.len());
        let mut pose = vec![0.0; cols.len()];
        let mut record = csv::StringRecord::new();
        loop {
            match rdr.read_record(&mut record) {
                Ok(false) => break,
                Ok(true) => {}
                Err(e) => {
                    let line = e.position().map(|p| p.line());
                    return Err(err(line, format!("malformed CSV: {}", csv_kind(&e))));
                }
            }
            let line = record.position().map(|p| p.line());
            let number = |k: usize, name: &str| -> Result<f64, FramesError> {
                let field = record.get(k).unwrap_or("");
                match field.trim().parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(err(line, format!("column '{name}' is not a finite number: '{field}'"))),
                }
            };
            let t = number(t_col, "t")?;
            if let Some(&last) = frames.times.last() {
                if t <= last {
                    return Err(err(line, format!("times must increase: t = {t} after {last}")));
                }
            }
            for (p, (k, name)) in pose.iter_mut().zip(&cols) {
                *p = number(*k, name)?;
            }
            frames.push(t, &pose);
        }
        if frames.is_empty() {
            return Err(err(None, "has no rows to replay".into()));
        }
        Ok(frames)
    }
}

/// The cause of a CSV error without the position (reported separately).
fn csv_kind(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
            format!("{len} fields where the header has {expected_len}")
        }
        csv::ErrorKind::Utf8 { .. } => "not valid UTF-8".into(),
        csv::ErrorKind::Io(io) => io.to_string(),
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_ends_and_spreads_evenly() {
        let mut f = Frames::new(1);
        for k in 0..=1000 {
            let t = k as f64 * 1e-3;
            f.push(t, &[t, 2.0 * t, 3.0 * t]);
        }
        let d = f.decimated(11);
        assert_eq!(d.len(), 11);
        for (i, t) in d.times.iter().enumerate() {
            // Frames 0, 100, …, 1000 of an evenly sampled run: t = i/10 exactly as sampled.
            assert_eq!(*t, (100 * i) as f64 * 1e-3);
            assert_eq!(&d.poses[3 * i..3 * i + 3], &[*t, 2.0 * t, 3.0 * t]);
        }
        assert_eq!(f.decimated(5000), f, "short runs are kept whole");
    }
}
