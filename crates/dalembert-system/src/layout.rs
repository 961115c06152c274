//! Where each body's coordinates sit in the system vectors.
//!
//! A system has `n_q` position coordinates `q` and `n_v` velocity coordinates `v`. They need not be
//! equal, and `v` need not be `q̇`: a spatial body with Euler parameters has seven positions and six
//! velocities (the angular velocity), and its positions advance by
//! [`crate::MultibodySystem::integrate_positions`]. Every body owns one contiguous block of `q` and
//! one of `v`; accelerations, forces and the columns of the constraint Jacobian use the `v` layout.

/// One body's blocks in the system vectors, with names for messages and output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BodyBlock {
    /// The body's name (errors and output name it).
    pub name: String,
    /// First index of the body's positions in `q`.
    pub q_offset: usize,
    /// Labels of the body's position coordinates (`x`, `y`, `angle`, …): their number is the block length.
    pub q_labels: &'static [&'static str],
    /// First index of the body's velocities in `v`.
    pub v_offset: usize,
    /// Labels of the body's velocity coordinates: their number is the block length.
    pub v_labels: &'static [&'static str],
}

impl BodyBlock {
    /// Number of position coordinates.
    #[inline]
    pub fn q_len(&self) -> usize {
        self.q_labels.len()
    }

    /// Number of velocity coordinates.
    #[inline]
    pub fn v_len(&self) -> usize {
        self.v_labels.len()
    }
}

/// The coordinate layout of a system: per-body blocks of `q` and `v`, contiguous, in body order.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Layout {
    bodies: Vec<BodyBlock>,
    n_q: usize,
    n_v: usize,
}

impl Layout {
    /// A layout of bodies in order, each with its position and velocity labels; offsets follow.
    pub fn new<'a>(
        bodies: impl IntoIterator<Item = (&'a str, &'static [&'static str], &'static [&'static str])>,
    ) -> Self {
        let mut layout = Layout::default();
        for (name, q_labels, v_labels) in bodies {
            layout.bodies.push(BodyBlock {
                name: name.to_string(),
                q_offset: layout.n_q,
                q_labels,
                v_offset: layout.n_v,
                v_labels,
            });
            layout.n_q += q_labels.len();
            layout.n_v += v_labels.len();
        }
        layout
    }

    /// Number of position coordinates `n_q`.
    #[inline]
    pub fn n_q(&self) -> usize {
        self.n_q
    }

    /// Number of velocity coordinates `n_v` (also of accelerations, forces, Jacobian columns).
    #[inline]
    pub fn n_v(&self) -> usize {
        self.n_v
    }

    /// The bodies' blocks, in order.
    #[inline]
    pub fn bodies(&self) -> &[BodyBlock] {
        &self.bodies
    }

    /// The body owning velocity coordinate `i`, and the coordinate's index within the body.
    pub fn velocity_owner(&self, i: usize) -> (&BodyBlock, usize) {
        let k = self.bodies.partition_point(|b| b.v_offset + b.v_len() <= i);
        let b = &self.bodies[k.min(self.bodies.len().saturating_sub(1))];
        (b, i - b.v_offset)
    }

    /// The body owning position coordinate `i`, and the coordinate's index within the body.
    pub fn position_owner(&self, i: usize) -> (&BodyBlock, usize) {
        let k = self.bodies.partition_point(|b| b.q_offset + b.q_len() <= i);
        let b = &self.bodies[k.min(self.bodies.len().saturating_sub(1))];
        (b, i - b.q_offset)
    }

    /// `"angle of body 'crank'"` for velocity coordinate `i`.
    pub fn describe_velocity(&self, i: usize) -> String {
        let (b, k) = self.velocity_owner(i);
        format!("{} of body '{}'", b.v_labels[k], b.name)
    }

    /// `"x of body 'crank'"` for position coordinate `i`.
    pub fn describe_position(&self, i: usize) -> String {
        let (b, k) = self.position_owner(i);
        format!("{} of body '{}'", b.q_labels[k], b.name)
    }

    /// True when positions and velocities share one layout (`n_q = n_v`, block by block), so that
    /// `v = q̇` is possible.
    pub fn velocities_are_position_rates(&self) -> bool {
        self.bodies.iter().all(|b| b.q_len() == b.v_len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const XYT: &[&str] = &["x", "y", "angle"];
    const Q7: &[&str] = &["x", "y", "z", "e0", "e1", "e2", "e3"];
    const V6: &[&str] = &["x", "y", "z", "wx", "wy", "wz"];

    /// Offsets are the running sums of the block lengths; owners invert them.
    #[test]
    fn offsets_and_owners_of_mixed_blocks() {
        let l = Layout::new([("a", XYT, XYT), ("b", Q7, V6), ("c", XYT, XYT)]);
        assert_eq!((l.n_q(), l.n_v()), (13, 12));
        assert_eq!(l.bodies()[2].q_offset, 10);
        assert_eq!(l.bodies()[2].v_offset, 9);
        assert_eq!(l.describe_velocity(8), "wz of body 'b'");
        assert_eq!(l.describe_position(9), "e3 of body 'b'");
        assert_eq!(l.describe_velocity(9), "x of body 'c'");
        assert!(!l.velocities_are_position_rates());
    }
}
