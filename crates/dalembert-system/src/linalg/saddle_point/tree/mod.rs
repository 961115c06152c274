//! Tree back end: a block `L D Lᵀ` factorization of the whole saddle-point matrix `[M C_qᵀ; C_q 0]`
//! ordered along the body–joint graph, with no fill-in, so its cost is linear in the number of
//! bodies with small dense blocks only (Baraff, "Linear-time dynamics using Lagrange multipliers",
//! SIGGRAPH 1996). Loops are closed by the Schur complement of the equations cut from the tree.
//!
//! **Graph.** The equations are grouped by the set of bodies they touch (a joint's equations, with
//! any driver between the same bodies). A group on one body links it to the ground, a group on two
//! bodies links them. A spanning forest is grown over these links (grounded groups first); every
//! other group, and every group on more than two bodies, is *cut*. Nodes are the bodies and the
//! groups of the forest; a grounded group is a root, a floating subtree's first body is a root.
//!
//! **Factorization** (`K_t` the matrix of bodies and tree groups, `D_i` node `i`'s diagonal block,
//! `K_ip` its block with its parent `p`). Children before parents:
//!
//! ```text
//! D_i = L_i Δ_i L_iᵀ,   Z_i = L_i⁻¹ K_ip,   W_i = Δ_i⁻¹ Z_i,   D_p ← D_p − Z_iᵀ W_i   (= K_piᵀ D_i⁻¹ K_ip)
//! ```
//!
//! (`L_i` unit lower triangular, `Δ_i` diagonal), starting from `D_body = M_b` and `D_group = 0`. A
//! body's block stays positive definite, a group's becomes `−J D_child⁻¹ Jᵀ`, negative definite when
//! the group's equations are independent on its child body: each is factored by the square-root-free
//! Cholesky with its expected sign ([`small_ldlt`]). Solve `K_t w = b`: children first
//! `y_i = L_i⁻¹ b_i`, `b_p −= W_iᵀ y_i`; then parents first `w_i = L_i⁻ᵀ (Δ_i⁻¹ y_i − W_i w_p)`.
//!
//! **Loops.** With `G` the cut equations' rows of `C_q` (over the bodies) and `Y = K_t⁻¹ Gᵀ` (one
//! tree solve per cut equation at factorization), `P = G Y` is positive definite when `C_q` has full
//! rank; then `μ = P⁻¹ (G K_t⁻¹ b_t − b_c)` and `w = K_t⁻¹ b_t − Y μ`. The cost grows with the number
//! of cut equations; [`Backend::Auto`](super::Backend::Auto) chooses this back end only for systems
//! without loops (loops are for an explicit [`Backend::Tree`](super::Backend::Tree)).
//!
//! **Singularity.** A Cholesky pivot below the tolerance relative to its block's diagonal, or a
//! ratio of the multiplier blocks' pivots (the groups' and `P`'s, as for the Schur complement) whose
//! square exceeds `1 / pivot_tolerance`.
//!
//! **Condition estimate.** Block elimination along a fixed order is unchanged by scaling each
//! node's unknowns (a body's translations against its rotations, one body's mass against
//! another's), so only each block's own loss of digits counts: the estimate is the inverse of the
//! smallest scale-free pivot decay `d_k / a_kk` over all blocks and `P`
//! ([`small_ldlt::Pivots::decay`]), and for `P`, a Schur complement over the loop closures, also
//! its pivot span as for the Schur back ends (without it a generated closed mechanism with a mass
//! ratio of 380 was solved 1.3e-9 off the dense LU, unrefined: `tests/agreement.rs`, the case kept
//! in its regressions file). Near a singular position of a closed chain `P` loses rank and the
//! estimate grows as for the Schur complement; a thin rod's inertia against its mass, or a mass
//! ratio between the bodies of a tree, does not make it grow.

mod kernels;

use super::SingularKkt;
use crate::linalg::small_ldlt;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintValues};
use kernels::Coupling;
use std::collections::HashMap;

/// A node of the forest: a body or a group of equations.
#[derive(Debug, Clone)]
struct Node {
    /// Rows and columns of its diagonal block.
    size: usize,
    /// `+1` for a body (positive definite block), `−1` for a group of equations.
    sign: f64,
    parent: Option<usize>,
    /// The body (mass block) of a body node.
    body: usize,
    /// Offset of its diagonal block in `TreeKkt::d`.
    d: usize,
    /// Offset of `W_i` (`size × parent size`) in `TreeKkt::couplings`.
    coupling: usize,
    /// Offset of its unknowns in the packed vector.
    at: usize,
    /// Edge to the parent: `edge_entries[edge..edge + rows]` are, for each equation of the group,
    /// the first Jacobian entry of its segment on the body (the body's coordinates follow).
    edge: usize,
    /// True when this node is the group side of the edge (`K_ip = J`), false for the body side
    /// (`K_ip = Jᵀ`).
    group_side: bool,
}

/// The forest under construction: nodes in breadth-first order (parents before children).
#[derive(Default)]
struct Forest {
    nodes: Vec<Node>,
    edge_entries: Vec<usize>,
    index: Vec<usize>,
}

impl Forest {
    fn add(
        &mut self,
        size: usize,
        sign: f64,
        body: usize,
        parent: Option<(usize, &[usize])>,
        group_side: bool,
    ) -> usize {
        let edge = self.edge_entries.len();
        if let Some((_, entries)) = parent {
            self.edge_entries.extend_from_slice(entries);
        }
        self.nodes.push(Node {
            size,
            sign,
            parent: parent.map(|p| p.0),
            body,
            d: 0,
            coupling: 0,
            at: self.index.len(),
            edge,
            group_side,
        });
        self.nodes.len() - 1
    }

    /// Body `b` under a group node (with the group's first entries on `b`).
    fn body(&mut self, mass: &BlockDiagonal, b: usize, parent: Option<(usize, &[usize])>) -> usize {
        let id = self.add(mass.size(b), 1.0, b, parent, false);
        self.index.extend(mass.offset(b)..mass.offset(b) + mass.size(b));
        id
    }

    /// Group `g` under a body node (with the group's first entries on that body).
    fn group(&mut self, groups: &Groups, g: usize, n: usize, parent: Option<(usize, &[usize])>) -> usize {
        let id = self.add(groups.rows[g].len(), -1.0, usize::MAX, parent, true);
        self.index.extend(groups.rows[g].iter().map(|r| n + r));
        id
    }
}

/// A cut equation's entries on one body: `(cut index, packed offset of the body, first entry, len)`.
type CutSegment = (usize, usize, usize, usize);

pub(crate) struct TreeKkt {
    n: usize,
    nodes: Vec<Node>,
    edge_entries: Vec<usize>,
    /// Global index of each packed unknown (bodies' velocities, tree groups' multipliers).
    index: Vec<usize>,
    /// The diagonal blocks' factors (`L_i` and `1 / d_k`), node by node.
    d: Vec<f64>,
    /// `W_i = Δ_i⁻¹ L_i⁻¹ K_ip`, node by node.
    couplings: Vec<f64>,
    jacobian: Vec<f64>,
    work: Vec<f64>,
    /// Cut equations (global rows), their segments, `Y` (column by column) and `P`'s factor.
    cut_rows: Vec<usize>,
    cut_segments: Vec<CutSegment>,
    y: Vec<f64>,
    p: Vec<f64>,
    mu: Vec<f64>,
    pivot_tolerance: f64,
    /// Squared ratio of the largest to the smallest multiplier-block pivot of the last
    /// factorization.
    pub condition: f64,
}

/// Equations grouped by the bodies they touch; `None` when some equation touches no body or one
/// body twice.
struct Groups {
    /// Per group: its rows, its bodies (sorted), and per body the first entry of each row's segment.
    rows: Vec<Vec<usize>>,
    bodies: Vec<Vec<usize>>,
    entries: Vec<Vec<Vec<usize>>>,
}

fn group_equations(pattern: &ConstraintPattern) -> Option<Groups> {
    let mut segs: Vec<Vec<(usize, usize)>> = vec![Vec::new(); pattern.rows()];
    for s in pattern.segments() {
        segs[s.row].push((s.body, s.first));
    }
    let mut g = Groups {
        rows: Vec::new(),
        bodies: Vec::new(),
        entries: Vec::new(),
    };
    let mut by_bodies: HashMap<Vec<usize>, usize> = HashMap::new();
    for (row, mut list) in segs.into_iter().enumerate() {
        list.sort_unstable();
        if list.is_empty() || list.windows(2).any(|w| w[0].0 == w[1].0) {
            return None;
        }
        let bodies: Vec<usize> = list.iter().map(|s| s.0).collect();
        let k = *by_bodies.entry(bodies.clone()).or_insert_with(|| {
            g.rows.push(Vec::new());
            g.entries.push(vec![Vec::new(); bodies.len()]);
            g.bodies.push(bodies);
            g.rows.len() - 1
        });
        g.rows[k].push(row);
        for (e, s) in g.entries[k].iter_mut().zip(&list) {
            e.push(s.1);
        }
    }
    Some(g)
}

fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// Number of equations the tree back end would cut to close loops, or `None` when it cannot run
/// on this pattern (an equation on no body, or listing a body twice, or blocks of sizes its
/// kernels are not made for: [`kernels::supported`]).
pub(crate) fn cut_rows(pattern: &ConstraintPattern, mass: &BlockDiagonal) -> Option<usize> {
    let groups = group_equations(pattern)?;
    let tree = spanning_forest(&groups, mass.num_blocks());
    let sizes_fit = (0..mass.num_blocks()).all(|b| kernels::supported(mass.size(b), 0))
        && (0..groups.rows.len()).filter(|&g| tree[g]).all(|g| {
            let rows = groups.rows[g].len();
            (groups.bodies[g].len() == 2 || kernels::supported(rows, 0))
                && groups.bodies[g]
                    .iter()
                    .all(|&b| kernels::supported(rows, mass.size(b)) && kernels::supported(mass.size(b), rows))
        });
    if !sizes_fit {
        return None;
    }
    Some(
        (0..groups.rows.len())
            .filter(|&g| !tree[g])
            .map(|g| groups.rows[g].len())
            .sum(),
    )
}

/// Which groups form the forest (grounded groups first, then in order; union–find over the bodies
/// and the ground).
fn spanning_forest(groups: &Groups, bodies: usize) -> Vec<bool> {
    let ground = bodies;
    let mut uf: Vec<usize> = (0..=bodies).collect();
    let mut tree = vec![false; groups.rows.len()];
    let order = (0..groups.rows.len())
        .filter(|&g| groups.bodies[g].len() == 1)
        .chain((0..groups.rows.len()).filter(|&g| groups.bodies[g].len() == 2));
    for g in order {
        let b = &groups.bodies[g];
        let (a, c) = if b.len() == 1 { (ground, b[0]) } else { (b[0], b[1]) };
        let (ra, rc) = (find(&mut uf, a), find(&mut uf, c));
        if ra != rc {
            uf[ra] = rc;
            tree[g] = true;
        }
    }
    tree
}

impl TreeKkt {
    /// The forest, storage and cut equations for `pattern` over `mass`'s bodies; `None` when the
    /// tree back end cannot run (see [`cut_rows`]).
    pub fn new(mass: &BlockDiagonal, pattern: &ConstraintPattern, pivot_tolerance: f64) -> Option<Self> {
        let nb = mass.num_blocks();
        let n = mass.dim();
        let groups = group_equations(pattern)?;
        let tree = spanning_forest(&groups, nb);
        let mut incident: Vec<Vec<usize>> = vec![Vec::new(); nb];
        for g in (0..groups.rows.len()).filter(|&g| tree[g] && groups.bodies[g].len() == 2) {
            for &b in &groups.bodies[g] {
                incident[b].push(g);
            }
        }
        let mut f = Forest::default();
        let mut visited = vec![false; nb];
        let mut queue = std::collections::VecDeque::new();
        for g in (0..groups.rows.len()).filter(|&g| tree[g] && groups.bodies[g].len() == 1) {
            let b = groups.bodies[g][0];
            let gid = f.group(&groups, g, n, None);
            let bid = f.body(mass, b, Some((gid, &groups.entries[g][0])));
            visited[b] = true;
            queue.push_back((b, bid, usize::MAX));
        }
        let mut next_root = 0..nb;
        loop {
            while let Some((b, bid, from)) = queue.pop_front() {
                for &g in incident[b].iter().filter(|&&g| g != from) {
                    let kb = usize::from(groups.bodies[g][0] != b);
                    let gid = f.group(&groups, g, n, Some((bid, &groups.entries[g][kb])));
                    let c = groups.bodies[g][1 - kb];
                    if visited[c] {
                        return None;
                    }
                    visited[c] = true;
                    let cid = f.body(mass, c, Some((gid, &groups.entries[g][1 - kb])));
                    queue.push_back((c, cid, g));
                }
            }
            match next_root.by_ref().find(|&b| !visited[b]) {
                Some(b) => {
                    visited[b] = true;
                    let bid = f.body(mass, b, None);
                    queue.push_back((b, bid, usize::MAX));
                }
                None => break,
            }
        }
        let Forest {
            mut nodes,
            edge_entries,
            index,
        } = f;
        let parent_size = |nd: &Node| nd.parent.map_or(0, |p| nodes[p].size);
        if !nodes.iter().all(|nd| kernels::supported(nd.size, parent_size(nd))) {
            return None;
        }
        // Storage offsets.
        let (mut d_len, mut w_len) = (0, 0);
        for i in 0..nodes.len() {
            nodes[i].d = d_len;
            d_len += nodes[i].size * nodes[i].size;
            if let Some(p) = nodes[i].parent {
                nodes[i].coupling = w_len;
                w_len += nodes[i].size * nodes[p].size;
            }
        }
        // Cut equations and their segments in packed body offsets.
        let mut packed_body = vec![0; nb];
        for node in nodes.iter().filter(|nd| nd.sign > 0.0) {
            packed_body[node.body] = node.at;
        }
        let mut cut_rows: Vec<usize> = (0..groups.rows.len())
            .filter(|&g| !tree[g])
            .flat_map(|g| groups.rows[g].iter().copied())
            .collect();
        cut_rows.sort_unstable();
        let mut cut_segments = Vec::new();
        for s in pattern.segments() {
            if let Ok(j) = cut_rows.binary_search(&s.row) {
                cut_segments.push((j, packed_body[s.body], s.first, s.len));
            }
        }
        let nt = index.len();
        let mc = cut_rows.len();
        Some(TreeKkt {
            n,
            nodes,
            edge_entries,
            index,
            d: vec![0.0; d_len],
            couplings: vec![0.0; w_len],
            jacobian: vec![
                0.0;
                if cut_rows.is_empty() {
                    0
                } else {
                    pattern.entries().len()
                }
            ],
            work: vec![0.0; nt],
            cut_rows,
            cut_segments,
            y: vec![0.0; nt * mc],
            p: vec![0.0; mc * mc],
            mu: vec![0.0; mc],
            pivot_tolerance,
            condition: 1.0,
        })
    }

    /// True when equations were cut to close loops.
    pub fn has_loops(&self) -> bool {
        !self.cut_rows.is_empty()
    }

    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        _pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        // The solve reads the Jacobian only for the cut equations' rows.
        if !self.cut_rows.is_empty() {
            self.jacobian.copy_from_slice(&vals.jacobian);
        }
        let jac = &vals.jacobian;
        // Diagonal blocks: M_b for bodies, 0 for groups.
        for node in &self.nodes {
            let d = &mut self.d[node.d..node.d + node.size * node.size];
            if node.sign > 0.0 {
                d.copy_from_slice(mass.block(node.body));
            } else {
                d.iter_mut().for_each(|v| *v = 0.0);
            }
        }
        // Pivot range of the multiplier blocks (singularity test, as for the Schur complement) and
        // the worst scale-free pivot decay of any block (condition estimate).
        let (mut dmin, mut dmax, mut decay) = (f64::INFINITY, 0.0f64, 1.0f64); // |d_k| range
        let mut loop_span = 1.0f64;
        for i in (0..self.nodes.len()).rev() {
            let node = &self.nodes[i];
            let si = node.size;
            let (head, tail) = self.d.split_at_mut(node.d);
            let di = &mut tail[..si * si];
            let (sp, parent) = match node.parent {
                Some(p) => {
                    let sp = self.nodes[p].size;
                    let coupling = Coupling {
                        jac,
                        edge: &self.edge_entries[node.edge..],
                        group_side: node.group_side,
                    };
                    let dp = &mut head[self.nodes[p].d..self.nodes[p].d + sp * sp];
                    (
                        sp,
                        Some((
                            coupling,
                            &mut self.couplings[node.coupling..node.coupling + si * sp],
                            dp,
                        )),
                    )
                }
                None => (0, None),
            };
            let pivots = kernels::eliminate(si, sp, node.sign, self.pivot_tolerance, di, parent).map_err(|d| {
                SingularKkt(format!(
                    "{} block pivot {d:.3e} (tree factorization)",
                    if node.sign > 0.0 { "body" } else { "equation" }
                ))
            })?;
            decay = decay.min(pivots.decay);
            if node.sign < 0.0 {
                dmin = dmin.min(pivots.min);
                dmax = dmax.max(pivots.max);
            }
        }
        // Loops: Y = K_t⁻¹ Gᵀ, P = G Y.
        let mc = self.cut_rows.len();
        if mc > 0 {
            let nt = self.index.len();
            self.y.iter_mut().for_each(|v| *v = 0.0);
            for &(j, w, first, len) in &self.cut_segments {
                self.y[j * nt + w..j * nt + w + len].copy_from_slice(&jac[first..first + len]);
            }
            for j in 0..mc {
                let mut col = std::mem::take(&mut self.work);
                col.copy_from_slice(&self.y[j * nt..(j + 1) * nt]);
                self.tree_solve(&mut col);
                self.y[j * nt..(j + 1) * nt].copy_from_slice(&col);
                self.work = col;
            }
            self.p.iter_mut().for_each(|v| *v = 0.0);
            for &(i, w, first, len) in &self.cut_segments {
                for j in 0..mc {
                    let yj = &self.y[j * nt + w..j * nt + w + len];
                    self.p[i * mc + j] += (0..len).map(|c| jac[first + c] * yj[c]).sum::<f64>();
                }
            }
            let pivots = small_ldlt::factor(&mut self.p, mc, 1.0, self.pivot_tolerance)
                .map_err(|d| SingularKkt(format!("loop-closure Schur complement pivot {d:.3e}")))?;
            dmin = dmin.min(pivots.min);
            dmax = dmax.max(pivots.max);
            decay = decay.min(pivots.decay);
            // P is a Schur complement over the loop closures: its pivot span, as for the Schur back
            // ends, is the estimate there.
            loop_span = pivots.max / pivots.min;
        }
        let span = if dmin > 0.0 { dmax / dmin } else { 1.0 };
        if span * self.pivot_tolerance > 1.0 {
            return Err(SingularKkt(format!(
                "multiplier pivots span {span:.3e} (tree factorization)"
            )));
        }
        self.condition = (1.0 / decay).max(loop_span);
        Ok(())
    }

    /// `w ← K_t⁻¹ w` on the packed tree unknowns: children first `y_i = L_i⁻¹ w_i`,
    /// `w_p −= W_iᵀ y_i`; then parents first `w_i = L_i⁻ᵀ (Δ_i⁻¹ y_i − W_i w_p)`.
    fn tree_solve(&self, w: &mut [f64]) {
        let nodes = &self.nodes;
        for node in nodes.iter().rev() {
            let si = node.size;
            let l = &self.d[node.d..node.d + si * si];
            let (head, tail) = w.split_at_mut(node.at);
            match node.parent {
                Some(p) => {
                    let sp = nodes[p].size;
                    let wc = &self.couplings[node.coupling..node.coupling + si * sp];
                    kernels::up(si, sp, l, wc, tail, &mut head[nodes[p].at..]);
                }
                None => kernels::root(si, l, tail),
            }
        }
        for node in nodes {
            let Some(p) = node.parent else { continue };
            let si = node.size;
            let sp = nodes[p].size;
            let l = &self.d[node.d..node.d + si * si];
            let wc = &self.couplings[node.coupling..node.coupling + si * sp];
            let (head, tail) = w.split_at_mut(node.at);
            kernels::down(si, sp, l, wc, tail, &head[nodes[p].at..]);
        }
    }

    pub fn solve(&mut self, x: &mut [f64]) {
        let mut w = std::mem::take(&mut self.work);
        for (v, &g) in w.iter_mut().zip(&self.index) {
            *v = x[g];
        }
        self.tree_solve(&mut w);
        let mc = self.cut_rows.len();
        if mc > 0 {
            let nt = self.index.len();
            for (j, &r) in self.cut_rows.iter().enumerate() {
                self.mu[j] = -x[self.n + r];
            }
            for &(j, off, first, len) in &self.cut_segments {
                self.mu[j] += (0..len).map(|c| self.jacobian[first + c] * w[off + c]).sum::<f64>();
            }
            small_ldlt::solve(&self.p, mc, &mut self.mu);
            for (j, &mu) in self.mu.iter().enumerate() {
                for (v, y) in w.iter_mut().zip(&self.y[j * nt..(j + 1) * nt]) {
                    *v -= y * mu;
                }
            }
            for (j, &r) in self.cut_rows.iter().enumerate() {
                x[self.n + r] = self.mu[j];
            }
        }
        for (v, &g) in w.iter().zip(&self.index) {
            x[g] = *v;
        }
        self.work = w;
    }
}
