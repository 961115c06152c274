//! Compliant contact among a group of capsules (`docs/contact.md`, "Groups and the broad
//! phase"): every two members on different bodies that no joint joins touch by the law of two
//! capsules ([`SweptPair`]), and a broad phase finds the pairs whose boxes overlap so that the
//! cost grows with the members, not with their pairs.
//!
//! Broad phase (sweep and prune): each member's axis-aligned box (its segment's ends' bounds
//! widened by its radius) is found at each evaluation; the members are kept sorted by their
//! boxes' lower ends along the axis along which the boxes' centres spread most, by insertion
//! sort from the last evaluation's order (a motion between two evaluations moves few members
//! past each other, so the sort costs about one pass); a sweep along the sorted list meets each
//! member's overlapping neighbours only. A pair is then the narrow phase's (the closest points of
//! the two segments) only where the boxes overlap along all three axes.

use super::contact::SweptPair;
use super::V3;
use crate::frame::Frame;
use dalembert_system::{ContactLaw, ContactResultant};
use std::sync::Mutex;

/// One capsule of a group.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Member {
    /// The body (`None`: the ground).
    pub body: Option<usize>,
    /// The segment's ends in the body frame.
    pub ends: [V3; 2],
    /// Radius (m).
    pub radius: f64,
}

/// The broad phase's storage, kept from one evaluation to the next.
#[derive(Debug, Clone, Default)]
struct Sweep {
    /// Members by their boxes' lower ends along `axis`.
    order: Vec<usize>,
    /// Each member's box: lower and upper ends along x, y, z (widened by `margin` / 2).
    boxes: Vec<[[f64; 3]; 2]>,
}

/// A group of capsules in mutual compliant contact.
#[derive(Debug)]
pub(crate) struct CapsuleGroup {
    /// The members.
    pub members: Vec<Member>,
    /// The pairs of bodies that touch no matter what (joined by a joint), `(lower, higher)`
    /// body index (`usize::MAX` for the ground), sorted: their members' pairs are skipped.
    pub joined: Vec<(usize, usize)>,
    /// The law.
    pub law: ContactLaw,
    /// The broad phase's storage (a lock: evaluations take `&self`; it is never contended).
    sweep: Mutex<Sweep>,
}

impl Clone for CapsuleGroup {
    fn clone(&self) -> Self {
        CapsuleGroup::new(self.members.clone(), self.joined.clone(), self.law)
    }
}

/// The widening of the boxes by which the gap reported for events is taken over the pairs
/// nearer than this share of the smallest radius ([`CapsuleGroup::gap`]).
const MARGIN_SHARE: f64 = 0.5;

impl CapsuleGroup {
    /// A group of `members`, skipping pairs of bodies in `joined` (any order).
    pub fn new(members: Vec<Member>, mut joined: Vec<(usize, usize)>, law: ContactLaw) -> Self {
        for pair in &mut joined {
            *pair = (pair.0.min(pair.1), pair.0.max(pair.1));
        }
        joined.sort_unstable();
        joined.dedup();
        let n = members.len();
        CapsuleGroup {
            members,
            joined,
            law,
            sweep: Mutex::new(Sweep {
                order: (0..n).collect(),
                boxes: vec![[[0.0; 3]; 2]; n],
            }),
        }
    }

    /// The pair of members `i`, `j` as two capsules.
    fn pair(&self, i: usize, j: usize) -> SweptPair {
        let (a, b) = (&self.members[i], &self.members[j]);
        SweptPair {
            ends: [(a.body, a.ends), (b.body, b.ends)],
            radii: [a.radius, b.radius],
            law: self.law,
        }
    }

    /// The margin of the event's gap: [`MARGIN_SHARE`] of the smallest radius.
    fn margin(&self) -> f64 {
        MARGIN_SHARE * self.members.iter().map(|m| m.radius).fold(f64::INFINITY, f64::min)
    }

    /// Calls `visit(i, j)` for each pair of members on different bodies not joined whose boxes,
    /// widened by `widen` on every side, overlap.
    fn candidates(&self, frame: &dyn Fn(Option<usize>) -> Frame, widen: f64, visit: &mut dyn FnMut(usize, usize)) {
        let mut guard = self.sweep.lock().unwrap_or_else(|p| p.into_inner());
        let sweep = &mut *guard;
        let (mut sum, mut square) = ([0.0f64; 3], [0.0f64; 3]);
        for (m, b) in self.members.iter().zip(sweep.boxes.iter_mut()) {
            let f = frame(m.body);
            let (p, q) = (f.point(&m.ends[0]), f.point(&m.ends[1]));
            for k in 0..3 {
                b[0][k] = p[k].min(q[k]) - m.radius - widen;
                b[1][k] = p[k].max(q[k]) + m.radius + widen;
                let c = 0.5 * (b[0][k] + b[1][k]);
                sum[k] += c;
                square[k] += c * c;
            }
        }
        // The axis along which the boxes' centres spread most.
        let n = self.members.len().max(1) as f64;
        let spread = |k: usize| square[k] / n - (sum[k] / n).powi(2);
        let axis = (0..3).max_by(|&a, &b| spread(a).total_cmp(&spread(b))).unwrap_or(0);
        let boxes = &sweep.boxes;
        // Insertion sort from the last order: about one pass when few members passed each other.
        let order = &mut sweep.order;
        for k in 1..order.len() {
            let mut i = k;
            while i > 0 && boxes[order[i - 1]][0][axis] > boxes[order[i]][0][axis] {
                order.swap(i - 1, i);
                i -= 1;
            }
        }
        for (k, &i) in order.iter().enumerate() {
            for &j in &order[k + 1..] {
                if boxes[j][0][axis] > boxes[i][1][axis] {
                    break;
                }
                let overlap = (0..3).all(|c| boxes[i][0][c] <= boxes[j][1][c] && boxes[j][0][c] <= boxes[i][1][c]);
                if overlap && self.may_touch(i, j) {
                    visit(i.min(j), i.max(j));
                }
            }
        }
    }

    /// True when members `i` and `j` are on different bodies that no joint joins.
    fn may_touch(&self, i: usize, j: usize) -> bool {
        let key = |b: Option<usize>| b.unwrap_or(usize::MAX);
        let (a, b) = (key(self.members[i].body), key(self.members[j].body));
        a != b && self.joined.binary_search(&(a.min(b), a.max(b))).is_err()
    }

    /// Adds the contact forces of the pairs that overlap.
    pub fn add(&self, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        self.candidates(frame, 0.0, &mut |i, j| self.pair(i, j).add(frame, out));
    }

    /// `Σ k δⁿ⁺¹ / (n + 1)` over the pairs that overlap.
    pub fn potential(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let mut sum = 0.0;
        self.candidates(frame, 0.0, &mut |i, j| sum += self.pair(i, j).potential(frame));
        sum
    }

    /// The event's gap: the least gap of the pairs, or the margin where every pair is farther
    /// apart than that (pairs whose boxes, widened by half the margin, do not overlap are: so the
    /// least of the margin and the gaps of the others is that of all pairs, continuous in time).
    pub fn gap(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let margin = self.margin();
        let mut least = margin;
        self.candidates(frame, 0.5 * margin, &mut |i, j| {
            least = least.min(-self.pair(i, j).overlap(frame));
        });
        least
    }

    /// The resultant: the deepest pair's (its force on the second member's body, where it acts),
    /// with the gap of [`CapsuleGroup::gap`] and the normal force summed over the pairs in
    /// contact.
    pub fn resultant(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> ContactResultant<3> {
        let mut deepest: Option<(f64, usize, usize)> = None;
        let mut normal = 0.0;
        self.candidates(frame, 0.0, &mut |i, j| {
            let pair = self.pair(i, j);
            let depth = pair.overlap(frame);
            if depth > 0.0 {
                normal += pair.resultant(frame).normal;
            }
            if deepest.is_none_or(|(d, _, _)| depth > d) {
                deepest = Some((depth, i, j));
            }
        });
        let mut out = match deepest {
            Some((_, i, j)) => self.pair(i, j).resultant(frame),
            None => ContactResultant::new(self.margin()),
        };
        out.gap = self.gap(frame);
        out.normal = normal;
        out
    }

    /// True without dissipation and friction.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joined_pairs_are_skipped_in_either_order() {
        let member = |body: Option<usize>| Member {
            body,
            ends: [V3::zeros(), V3::x()],
            radius: 0.1,
        };
        let law = ContactLaw {
            stiffness: 1.0,
            exponent: 1.5,
            dissipation: 0.0,
            friction: 0.0,
            smoothing_velocity: 1e-3,
        };
        let group = CapsuleGroup::new(
            vec![
                member(Some(0)),
                member(Some(1)),
                member(Some(2)),
                member(None),
                member(Some(2)),
            ],
            vec![(1, 0), (usize::MAX, 2)],
            law,
        );
        assert!(!group.may_touch(0, 1) && !group.may_touch(1, 0));
        assert!(!group.may_touch(2, 3) && !group.may_touch(3, 2));
        assert!(!group.may_touch(2, 4), "one body's two members");
        assert!(group.may_touch(0, 2) && group.may_touch(1, 3) && group.may_touch(0, 3));
    }
}
