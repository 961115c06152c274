//! The motion to play: poses of every body at a sequence of times, from a run or from a result CSV.

use super::Drawing;
use crate::output::{read_columns, ResultCsvError};
use std::io::Read;

/// Poses of every body at increasing times: `[x, y, angle]` (planar) or `[x, y, z, e0, e1, e2,
/// e3]` (spatial) per body.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Frames {
    /// Times (s), increasing.
    pub times: Vec<f64>,
    /// Poses, frame after frame: `per_body × bodies` numbers per frame.
    pub poses: Vec<f64>,
    /// Number of bodies.
    pub bodies: usize,
    /// Numbers per body in a pose: 3 (planar) or 7 (spatial).
    pub per_body: usize,
    /// Forces to draw as arrows, frame after frame (empty: none recorded): per joint of a spatial
    /// drawing the force its second body exerts on its first, global components, then per
    /// compliant contact its force on its body and the point where it acts
    /// ([`Frames::reaction_columns`]).
    pub reactions: Vec<f64>,
}

impl Frames {
    /// No frames yet, for `bodies` planar bodies.
    pub fn new(bodies: usize) -> Self {
        Frames {
            bodies,
            per_body: 3,
            ..Frames::default()
        }
    }

    /// No frames yet, for the bodies of `drawing` (planar or spatial).
    pub fn for_drawing(drawing: &Drawing) -> Self {
        Frames {
            bodies: drawing.body_names().len(),
            per_body: drawing.pose_columns().len(),
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

    /// Appends the frame at `t` from the system positions `q` (`[x, y, θ]` or `[x, y, z, e0,
    /// e1, e2, e3]` per body).
    pub fn push(&mut self, t: f64, q: &[f64]) {
        debug_assert_eq!(q.len(), self.per_body * self.bodies);
        self.times.push(t);
        self.poses.extend_from_slice(q);
    }

    /// Appends the joint reactions of the frame last pushed (the values of
    /// [`Frames::reaction_columns`], in order).
    pub fn push_reactions(&mut self, forces: &[f64]) {
        self.reactions.extend_from_slice(forces);
    }

    /// The output columns of the forces a drawing's arrows show: a spatial drawing's joints'
    /// reactions (each joint's `fx, fy, fz`) then its compliant contacts' forces (each
    /// contact's `fx, fy, fz, px, py, pz`), a planar drawing's rigid contacts' normal forces
    /// (each one's `<name>.normal`) then its compliant contacts' forces (`fx, fy, px, py`).
    pub fn reaction_columns(drawing: &Drawing) -> Vec<String> {
        match drawing.spatial.as_ref() {
            Some(s) => {
                let joints = s
                    .joints
                    .iter()
                    .flat_map(|j| ["fx", "fy", "fz"].map(|c| format!("{}.{c}", j.name)));
                let contacts =
                    (s.contacts.iter()).flat_map(|k| ["fx", "fy", "fz", "px", "py", "pz"].map(|c| format!("{k}.{c}")));
                joints.chain(contacts).collect()
            }
            None => {
                let rigid = drawing.marks.iter().filter_map(|m| match m {
                    super::Mark::Contact { name, force: true, .. } => Some(format!("{name}.normal")),
                    _ => None,
                });
                let compliant =
                    (drawing.contacts.iter()).flat_map(|k| ["fx", "fy", "px", "py"].map(|c| format!("{k}.{c}")));
                rigid.chain(compliant).collect()
            }
        }
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
        let mut out = Frames {
            bodies: self.bodies,
            per_body: self.per_body,
            ..Frames::default()
        };
        let w = self.per_body * self.bodies;
        let r = self.reactions.len() / n;
        for i in 0..max {
            let k = ((i as f64) * (n - 1) as f64 / (max - 1) as f64).round() as usize;
            out.push(self.times[k], &self.poses[k * w..(k + 1) * w]);
            out.push_reactions(&self.reactions[k * r..(k + 1) * r]);
        }
        out
    }

    /// The output columns that hold the poses of `drawing`'s bodies, in a frame's order.
    pub fn columns(drawing: &Drawing) -> Vec<String> {
        let names = drawing.body_names();
        let pose = drawing.pose_columns();
        names
            .iter()
            .flat_map(|b| pose.iter().map(move |c| format!("{b}.{c}")))
            .collect()
    }

    /// Reads the frames of `drawing`'s bodies from a result CSV written by `simulate` (columns `t`
    /// and each body's pose, [`Frames::columns`]; other columns are ignored). `origin` names the
    /// file in errors: a missing column, a field that is not a finite number, times that do not
    /// increase.
    pub fn from_csv(reader: impl Read, drawing: &Drawing, origin: &str) -> Result<Frames, ResultCsvError> {
        let mut text = Vec::new();
        let mut reader = reader;
        reader.read_to_end(&mut text).map_err(|e| ResultCsvError {
            file: origin.to_string(),
            line: None,
            message: format!("cannot be read: {e}"),
        })?;
        let names = Frames::columns(drawing);
        let table = read_columns(text.as_slice(), origin, &names).map_err(|mut e| {
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
        // The joints' reactions where the file has them (a CSV of `simulate` does).
        let forces = Frames::reaction_columns(drawing);
        let reactions = match forces.is_empty() {
            true => Vec::new(),
            false => read_columns(text.as_slice(), origin, &forces).map_or(Vec::new(), |r| r.values),
        };
        Ok(Frames {
            times: table.times,
            poses: table.values,
            reactions,
            ..Frames::for_drawing(drawing)
        })
    }

    /// The frames of a run's rows (`names` the columns of `rows`, `t` first): the poses of
    /// `drawing`'s bodies ([`Frames::columns`]) and, where the rows have them, the joints'
    /// reactions. `None` names a missing pose column.
    pub fn from_rows<'r>(
        drawing: &Drawing,
        names: &[String],
        rows: impl Iterator<Item = &'r [f64]>,
    ) -> Result<Frames, String> {
        let index = |n: &String| names.iter().position(|c| c == n);
        let poses = Frames::columns(drawing)
            .iter()
            .map(|n| index(n).ok_or_else(|| format!("no column '{n}' in the run")))
            .collect::<Result<Vec<_>, _>>()?;
        let forces: Option<Vec<usize>> = Frames::reaction_columns(drawing).iter().map(index).collect();
        let mut frames = Frames::for_drawing(drawing);
        let mut q = vec![0.0; poses.len()];
        let mut f = Vec::new();
        for row in rows {
            q.iter_mut().zip(&poses).for_each(|(x, &k)| *x = row[k]);
            frames.push(row[0], &q);
            if let Some(forces) = &forces {
                f.clear();
                f.extend(forces.iter().map(|&k| row[k]));
                frames.push_reactions(&f);
            }
        }
        Ok(frames)
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
