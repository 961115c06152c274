//! The motion to play: poses of every body at a sequence of times, from a run or from a result CSV.

use super::Drawing;
use crate::output::{read_columns, ResultCsvError};
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
    pub fn from_csv(reader: impl Read, drawing: &Drawing, origin: &str) -> Result<Frames, ResultCsvError> {
        let names: Vec<String> = drawing
            .bodies
            .iter()
            .flat_map(|b| ["x", "y", "angle"].map(|c| format!("{}.{c}", b.name)))
            .collect();
        let table = read_columns(reader, origin, &names).map_err(|mut e| {
            if e.line == Some(1) && e.message.starts_with("no column") {
                e.message = format!("does not match the scene: {}", e.message);
            }
            e
        })?;
        if table.times.is_empty() {
            return Err(ResultCsvError {
                file: origin.to_string(),
                line: None,
                message: "has no rows to replay".into(),
            });
        }
        Ok(Frames {
            times: table.times,
            poses: table.values,
            bodies: drawing.bodies.len(),
        })
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
