//! The sparsity of the tangent of the dynamic residual `r = M(q) q̈ + C_qᵀ λ − Q(t, q, v)` with
//! respect to the positions (along the velocity coordinates, `q ⊕ ε e_j`) and the velocities, and
//! the grouping of its columns for finite differences.
//!
//! A velocity coordinate of body `a` can change the residual of body `b` only when `a` and `b` share
//! a mass block (`a = b`), a constraint equation (`C_qᵀ λ` of that equation reads and loads the
//! bodies of its [`Segment`](crate::Segment)s), or an applied-force element
//! ([`MultibodySystem::force_coupling`]; an element whose bodies are unknown couples every body).
//! The pattern of `∂r/∂q` and `∂r/∂v` is the union of those body blocks.
//!
//! Columns whose row sets do not meet can be perturbed together and read off one residual
//! difference (Curtis, Powell & Reid, *J. Inst. Math. Appl.* 13, 1974). Bodies are coloured greedily
//! so that two bodies of one colour have no coupled body in common (a distance-2 colouring of the
//! body graph); a *pass* perturbs coordinate `k` of every body of one colour. A chain needs three
//! colours, so its tangent costs `3 × (velocities per body)` residual differences whatever its
//! length, instead of one per coordinate.

use crate::MultibodySystem;
use std::ops::Range;

/// Pattern of the `n_v × n_v` tangent blocks and the column passes of its finite differences.
#[derive(Debug, Clone)]
pub struct TangentPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    passes: Vec<Vec<usize>>,
}

impl TangentPattern {
    /// The pattern of `system`'s tangent.
    pub fn new(system: &dyn MultibodySystem) -> Self {
        let layout = system.layout();
        let nb = layout.bodies().len();
        // Groups of mutually coupled bodies: constraint equations, then force elements.
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let pattern = system.constraints().pattern();
        let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); pattern.rows()];
        for s in pattern.segments() {
            by_row[s.row].push(s.body);
        }
        groups.extend(by_row.into_iter().filter(|g| g.len() > 1));
        match system.force_coupling() {
            Some(forces) => groups.extend(forces.into_iter().filter(|g| g.len() > 1)),
            None => groups.push((0..nb).collect()),
        }
        let mut neighbours: Vec<Vec<usize>> = (0..nb).map(|b| vec![b]).collect();
        for g in &groups {
            for &a in g {
                neighbours[a].extend_from_slice(g);
            }
        }
        for list in &mut neighbours {
            list.sort_unstable();
            list.dedup();
        }
        // Compressed columns: column j of body a has the rows of every coupled body.
        let n = layout.n_v();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for a in 0..nb {
            for _ in 0..layout.bodies()[a].v_len() {
                for &b in &neighbours[a] {
                    let blk = &layout.bodies()[b];
                    row_idx.extend(blk.v_offset..blk.v_offset + blk.v_len());
                }
                col_ptr.push(row_idx.len());
            }
        }
        // Greedy distance-2 colouring: a body takes the first colour not used by any body within
        // two steps (sharing a coupled body).
        let mut colour = vec![usize::MAX; nb];
        let mut used = Vec::new();
        let mut colours = 0;
        for a in 0..nb {
            used.clear();
            for &b in &neighbours[a] {
                for &c in &neighbours[b] {
                    if colour[c] != usize::MAX {
                        used.push(colour[c]);
                    }
                }
            }
            let k = (0..).find(|k| !used.contains(k)).unwrap_or(0);
            colour[a] = k;
            colours = colours.max(k + 1);
        }
        let mut passes = Vec::new();
        for k in 0..colours {
            let members: Vec<usize> = (0..nb).filter(|&a| colour[a] == k).collect();
            let widest = members.iter().map(|&a| layout.bodies()[a].v_len()).max().unwrap_or(0);
            for i in 0..widest {
                passes.push(
                    members
                        .iter()
                        .map(|&a| &layout.bodies()[a])
                        .filter(|b| i < b.v_len())
                        .map(|b| b.v_offset + i)
                        .collect(),
                );
            }
        }
        TangentPattern {
            n,
            col_ptr,
            row_idx,
            passes,
        }
    }

    /// Number of velocity coordinates `n_v` (rows and columns).
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of structural non-zeros.
    pub fn len(&self) -> usize {
        self.row_idx.len()
    }

    /// True when the pattern has no entries.
    pub fn is_empty(&self) -> bool {
        self.row_idx.is_empty()
    }

    /// The entries `(row, column)` in column order: entry `e` of the values is the `e`-th.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.n).flat_map(move |j| self.rows(j).iter().map(move |&i| (i, j)))
    }

    /// Indices of column `j`'s entries in the values.
    pub fn column(&self, j: usize) -> Range<usize> {
        self.col_ptr[j]..self.col_ptr[j + 1]
    }

    /// The rows of column `j`'s entries.
    pub fn rows(&self, j: usize) -> &[usize] {
        &self.row_idx[self.column(j)]
    }

    /// The index of entry `(i, j)` in the values, or `None` when it is outside the pattern.
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        self.rows(j).binary_search(&i).ok().map(|k| self.col_ptr[j] + k)
    }

    /// Groups of columns no two of which share a row: each is perturbed at once in one residual
    /// difference.
    pub fn passes(&self) -> &[Vec<usize>] {
        &self.passes
    }
}

/// The tangent's values on a [`TangentPattern`], as a system's analytic derivatives fill them
/// ([`MultibodySystem::residual_tangent`]): `∂r/∂q` (along the velocity coordinates) and `∂r/∂v`,
/// in the pattern's entry order.
pub struct TangentValues<'a> {
    pattern: &'a TangentPattern,
    dq: &'a mut [f64],
    dv: &'a mut [f64],
    outside: bool,
}

impl<'a> TangentValues<'a> {
    /// Zeroes `dq` and `dv` (each of the pattern's length) for the derivatives to be added.
    pub fn new(pattern: &'a TangentPattern, dq: &'a mut [f64], dv: &'a mut [f64]) -> Self {
        dq.fill(0.0);
        dv.fill(0.0);
        TangentValues {
            pattern,
            dq,
            dv,
            outside: false,
        }
    }

    fn entry(&mut self, i: usize, j: usize) -> Option<usize> {
        let found = self.pattern.position(i, j);
        self.outside |= found.is_none();
        found
    }

    /// Adds `value` to `∂r_i/∂q_j` (velocity coordinates `i`, `j`).
    #[inline]
    pub fn add_q(&mut self, i: usize, j: usize, value: f64) {
        if let Some(e) = self.entry(i, j) {
            self.dq[e] += value;
        }
    }

    /// Adds `value` to `∂r_i/∂v_j`.
    #[inline]
    pub fn add_v(&mut self, i: usize, j: usize, value: f64) {
        if let Some(e) = self.entry(i, j) {
            self.dv[e] += value;
        }
    }

    /// True when some derivative fell outside the pattern (an element coupling bodies it did not
    /// declare): the values are then incomplete and must not be used.
    pub fn outside(&self) -> bool {
        self.outside
    }
}
