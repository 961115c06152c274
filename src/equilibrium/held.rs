//! Equilibria against joint limits (`docs/statics.md`, "Joint limits"): a limit held at one of
//! its bounds is one more equation of the static problem, `s(q) = bound`, whose multiplier is the
//! stop's force along the joint; which limits are held is found by an active set ([`next`]).

use dalembert_system::limit::unwrap_angle;
use dalembert_system::{JointLimit, MultibodySystem, SlipRow};
use nalgebra::DMatrix;

/// A limit held at one of its bounds: its index among the system's limits and the bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Held {
    pub limit: usize,
    pub bound: f64,
}

impl Held {
    /// `+1` at the lower bound, `−1` at the upper: the sign of a force that pushes
    /// (`docs/limits.md`, (L2)).
    fn sign(&self, limit: &JointLimit) -> f64 {
        if self.bound == limit.lower {
            1.0
        } else {
            -1.0
        }
    }
}

/// The held limits' rows `g` (the rate of each joint's coordinate, `ṡ = g·v`) at a position,
/// their entries in a fixed order (that of the first position), and how far each coordinate is
/// from its bound there.
pub(crate) struct HeldRows {
    rows: Vec<SlipRow>,
    /// Each row's velocity coordinates, in the order of its entries.
    pub cols: Vec<Vec<usize>>,
    /// Zero velocities (a row's rate is not read at rest).
    rest: Vec<f64>,
}

/// The coordinate `raw` of `limit` on the turn nearest to `near` (a coordinate measured within a
/// turn, `(−π, π]`, is followed across it: bounds may lie beyond ±π); others as they are.
fn coordinate(limit: &JointLimit, raw: f64, near: f64) -> f64 {
    if limit.within_turn {
        unwrap_angle(near, raw)
    } else {
        raw
    }
}

impl HeldRows {
    /// The rows of `held` at `q`.
    pub fn new(system: &dyn MultibodySystem, q: &[f64], held: &[Held]) -> Self {
        let rest = vec![0.0; system.layout().n_v()];
        let mut rows = vec![SlipRow::default(); held.len()];
        for (row, h) in rows.iter_mut().zip(held) {
            system.limit_row(h.limit, 0.0, q, &rest, row);
        }
        let cols = rows.iter().map(|r| r.entries().iter().map(|e| e.0).collect()).collect();
        HeldRows { rows, cols, rest }
    }

    /// Refreshes the rows at `q` and writes each coordinate's distance from its bound into
    /// `violation`; false where a row's entries moved to other coordinates (not for a joint
    /// between two fixed bodies, whose row keeps its coordinates).
    pub fn at(&mut self, system: &dyn MultibodySystem, q: &[f64], held: &[Held], violation: &mut [f64]) -> bool {
        let limits = system.limits();
        let mut same = true;
        for (((row, h), cols), out) in self.rows.iter_mut().zip(held).zip(&self.cols).zip(violation) {
            let raw = system.limit_row(h.limit, 0.0, q, &self.rest, row);
            *out = coordinate(&limits[h.limit], raw, h.bound) - h.bound;
            same &= row.entries().len() == cols.len() && row.entries().iter().zip(cols).all(|(e, &c)| e.0 == c);
        }
        same
    }

    /// The rows' values, in the order of [`HeldRows::cols`], into `out`.
    pub fn values(&self, out: &mut [f64]) {
        let values = self.rows.iter().flat_map(|r| r.entries().iter().map(|e| e.1));
        out.iter_mut().zip(values).for_each(|(o, v)| *o = v);
    }

    /// `r += Σ g_j μ_j`.
    pub fn add(&self, mu: &[f64], r: &mut [f64]) {
        for (row, &m) in self.rows.iter().zip(mu) {
            for &(i, g) in row.entries() {
                r[i] += g * m;
            }
        }
    }

    /// The rows as a dense matrix (`held × n`).
    pub fn dense(&self, n: usize) -> DMatrix<f64> {
        let mut g = DMatrix::zeros(self.rows.len(), n);
        for (j, row) in self.rows.iter().enumerate() {
            for &(i, v) in row.entries() {
                g[(j, i)] += v;
            }
        }
        g
    }
}

/// The admissible motions restricted to those that keep the held limits' coordinates
/// (`G B x = 0`): `B N`, `Nᵀ K_r N`, …, with `N` a basis of the null space of `G B` (its
/// eigenvectors of `(G B)ᵀ G B` with eigenvalues below `10⁻¹²` of the largest).
pub(crate) fn restrict(reduced: super::Reduced, g: &DMatrix<f64>) -> super::Reduced {
    let gb = g * &reduced.b;
    let dof = gb.ncols();
    if dof == 0 || gb.nrows() == 0 {
        return reduced;
    }
    let gram = gb.transpose() * &gb;
    let eig = gram.clone().symmetric_eigen();
    let largest = eig.eigenvalues.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let keep: Vec<usize> = (0..dof).filter(|&i| eig.eigenvalues[i] <= 1e-12 * largest).collect();
    let mut basis = DMatrix::zeros(dof, keep.len());
    for (c, &i) in keep.iter().enumerate() {
        basis.set_column(c, &eig.eigenvectors.column(i));
    }
    let within = |x: &DMatrix<f64>| basis.transpose() * x * &basis;
    super::Reduced {
        b: &reduced.b * &basis,
        k: within(&reduced.k),
        d: within(&reduced.d),
        m: within(&reduced.m),
    }
}

/// How near (relative to `1 + |bound|`) a limit's coordinate lies to a bound where the motion
/// came to rest for the limit to be held there ([`reached`]): the run's stop holds its joint
/// where its impact was located (1e-10 m from the bound, measured on a slider), and a limit held
/// that needs no force lets go again ([`next`]).
const RESTING: f64 = 1e-6;

/// The limits at `q` whose coordinate lies at, beyond or within `within (1 + |b|)` of a bound
/// `b`, each held at that bound (the one it lies nearer or beyond), with how far beyond it the
/// coordinate lies (negative: short of it).
fn at_bounds(system: &dyn MultibodySystem, q: &[f64], within: f64) -> Vec<(f64, Held)> {
    let v = vec![0.0; system.layout().n_v()];
    let mut row = SlipRow::default();
    let limits = system.limits();
    (0..limits.len())
        .filter_map(|k| {
            let limit = &limits[k];
            let raw = system.limit_row(k, 0.0, q, &v, &mut row);
            // A coordinate within a turn, measured on the turn nearest the middle of the range.
            let middle = 0.5 * (limit.lower + limit.upper);
            let s = if middle.is_finite() {
                coordinate(limit, raw, middle)
            } else {
                raw
            };
            let (below, above) = (limit.lower - s, s - limit.upper);
            let (beyond, bound) = if below >= above {
                (below, limit.lower)
            } else {
                (above, limit.upper)
            };
            let near = bound.is_finite() && beyond >= -within * (1.0 + bound.abs());
            near.then_some((beyond, Held { limit: k, bound }))
        })
        .collect()
}

/// The limits at, beyond or within [`RESTING`] of a bound at `q` (a position where the motion
/// came to rest against its stops), each held at that bound.
pub(crate) fn reached(system: &dyn MultibodySystem, q: &[f64]) -> Vec<Held> {
    at_bounds(system, q, RESTING).into_iter().map(|(_, h)| h).collect()
}

/// The next set of held limits after an equilibrium at `q` with `held` held and each limit's force
/// `forces` (the system's limits; zero where free), or `None` when it is the answer: a held limit
/// whose force pulls (below `−tolerance`) lets go, the one pulling most first; otherwise a free
/// limit at or beyond a bound is held there, the one farthest beyond first.
pub(crate) fn next(
    system: &dyn MultibodySystem,
    q: &[f64],
    held: &[Held],
    forces: &[f64],
    tolerance: f64,
) -> Option<Vec<Held>> {
    let limits = system.limits();
    let pulling = (held.iter().enumerate())
        .map(|(j, h)| (j, h.sign(&limits[h.limit]) * forces[h.limit]))
        .filter(|&(_, f)| f < -tolerance)
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((j, _)) = pulling {
        let mut next = held.to_vec();
        next.remove(j);
        return Some(next);
    }
    let beyond = at_bounds(system, q, 0.0)
        .into_iter()
        .filter(|(_, h)| held.iter().all(|x| x.limit != h.limit))
        .max_by(|a, b| a.0.total_cmp(&b.0));
    beyond.map(|(_, h)| {
        let mut next = held.to_vec();
        next.push(h);
        next
    })
}
