//! The iteration matrix of generalized-α's Newton method,
//!
//! ```text
//! [ M + β' ∂r/∂q + γ' ∂r/∂v   C_qᵀ ]        r = M(q) q̈ + C_qᵀ λ − Q(t, q, v),
//! [ C_q                       0    ]
//! ```
//!
//! on the sparsity the system declares ([`TangentPattern`]: mass blocks, bodies sharing a
//! constraint equation or a force element) and factored by [`PatternLu`] (dense LU up to
//! [`PatternLu::DENSE_LIMIT`] unknowns, sparse LU with its symbolic analysis done once above).
//!
//! The tangent `∂r/∂q` (along the velocity coordinates, `q ⊕ ε e_j`) and `∂r/∂v` is the system's
//! analytic one where it has it ([`MultibodySystem::residual_tangent`]); otherwise it is formed by
//! central differences of the residual, with the columns that share no row perturbed together
//! (the pattern's passes: `4 × passes` residuals, 36 for any planar chain instead of `4 n`). It is
//! kept between refactorizations: [`IterationMatrix::refresh`] rebuilds the matrix from the mass
//! and constraint Jacobian at the current state and the kept tangent, which is what changes
//! fastest (`β' ∂r/∂q` and `γ' ∂r/∂v` are `O(h²)` and `O(h)` against `M`); a slow Newton
//! contraction makes the caller differentiate again ([`IterationMatrix::differentiate`]).
//!
//! Redundant constraints (minimum-norm treatment, [`IterationMatrix::new`] given the dropped
//! equations `D` of a maximal independent set `R`): the matrix above is singular, so each dropped
//! row and column is replaced by the identity (its `C_q` row and `C_qᵀ` column zeroed, a 1 on the
//! diagonal); with a zero residual there the Newton update leaves `λ_D = 0`, and the iteration is
//! that of the independent equations, whose solution is the same motion. The saddle-point
//! factorization without the tangent terms is set up on `R` alone.

use dalembert_system::linalg::{Backend, LinalgError, PatternLu, SaddlePoint};
use dalembert_system::{BlockDiagonal, ConstraintValues, MultibodySystem, ResidualTangent, TangentPattern};

/// Largest `(β' ‖∂r/∂q‖ + γ' ‖∂r/∂v‖) / ‖M‖` (row-sum norms) for which the tangent terms are
/// dropped from the matrix: Newton then contracts by about that ratio per iteration.
const KKT_LIMIT: f64 = 1e-2;
/// The augmented formulation's defaults for the saddle-point back end
/// (`dalembert_augmented::AugmentedOptions`).
pub(super) const KKT_DENSE_LIMIT: usize = 60;
pub(super) const KKT_PIVOT_TOLERANCE: f64 = 1e-13;

/// The tangent, the matrix's storage and its factors.
pub(crate) struct IterationMatrix {
    /// `∂r/∂q` and `∂r/∂v` over the tangent's entries, from the last differentiation.
    tangent: ResidualTangent,
    /// Whether `dr_dq`, `dr_dv` hold a differentiation, and whether it was the analytic one.
    differentiated: bool,
    analytic: bool,
    /// Row-sum norms of `dr_dq` and `dr_dv` (the size of the tangent terms against `M`).
    norms: (f64, f64),
    /// Entries: the tangent's, then the mass blocks', then `C_q` and `C_qᵀ`.
    lu: PatternLu,
    /// The saddle-point matrix `[M C_qᵀ; C_q 0]` without the tangent terms, factored as the
    /// augmented formulation factors it (`None` when it cannot be set up for this system).
    kkt: Option<SaddlePoint>,
    /// Whether the last factorization is `kkt`'s.
    uses_kkt: bool,
    /// Redundant constraints: the independent equations `R` (the pattern `kkt` is set up on, with
    /// the index of each of its entries in the system's values, and its values), the entries of
    /// the dropped rows, and `(n + |R|)` scratch for `kkt`'s solves. `None` without redundancy.
    reduced: Option<Reduced>,
    /// Scratch of `n_v` (row sums).
    v: Vec<f64>,
}

/// The independent equations of a redundant system (see the module documentation).
struct Reduced {
    rows: Vec<usize>,
    dropped: Vec<usize>,
    pattern: dalembert_system::ConstraintPattern,
    entries: Vec<usize>,
    values: ConstraintValues,
    dropped_entries: Vec<usize>,
    x: Vec<f64>,
}

/// The trial state a matrix is built at: the state a tangent is taken at.
pub(crate) use dalembert_system::TangentAt as Trial;

impl IterationMatrix {
    /// Storage for `system`'s iteration matrix; `independent`: the independent equations of a
    /// redundant system (the others are masked), `None` for all. `Err` when the sparse symbolic
    /// analysis fails.
    pub fn new(
        system: &dyn MultibodySystem,
        mass: &BlockDiagonal,
        independent: Option<Vec<usize>>,
    ) -> Result<Self, LinalgError> {
        let tangent = ResidualTangent::new(system);
        let n = tangent.pattern().dim();
        let pattern = system.constraints().pattern();
        let m = pattern.rows();
        let mut entries: Vec<(usize, usize)> = tangent.pattern().entries().collect();
        entries.extend(mass.entries().map(|(r, c, _)| (r, c)));
        entries.extend(pattern.entries().iter().map(|&(r, c)| (n + r, c)));
        entries.extend(pattern.entries().iter().map(|&(r, c)| (c, n + r)));
        let reduced = independent.map(|rows| {
            let mut kept = vec![false; m];
            rows.iter().for_each(|&r| kept[r] = true);
            let dropped: Vec<usize> = (0..m).filter(|&r| !kept[r]).collect();
            let dropped_entries = (pattern.entries().iter().enumerate())
                .filter(|(_, &(r, _))| !kept[r])
                .map(|(e, _)| e)
                .collect();
            let (sub, map) = pattern.subset(&rows);
            Reduced {
                x: vec![0.0; n + rows.len()],
                values: ConstraintValues::new(&sub, 0),
                pattern: sub,
                entries: map,
                rows,
                dropped,
                dropped_entries,
            }
        });
        if let Some(r) = &reduced {
            entries.extend(r.dropped.iter().map(|&d| (n + d, n + d)));
        }
        let k = n + m;
        let lu = PatternLu::new(k, entries, PatternLu::DENSE_LIMIT)?;
        let kkt_pattern = reduced.as_ref().map_or(pattern, |r| &r.pattern);
        let kkt = SaddlePoint::on_pattern(
            Backend::Auto,
            mass,
            system.mass_is_constant(),
            kkt_pattern,
            KKT_DENSE_LIMIT,
            KKT_PIVOT_TOLERANCE,
        )
        .ok();
        Ok(IterationMatrix {
            differentiated: false,
            analytic: false,
            norms: (0.0, 0.0),
            tangent,
            lu,
            kkt,
            uses_kkt: false,
            reduced,
            v: vec![0.0; n],
        })
    }

    /// Whether the last differentiation used the system's analytic tangent.
    #[cfg(test)]
    pub fn is_analytic(&self) -> bool {
        self.analytic
    }

    /// Whether a tangent is held.
    pub fn is_differentiated(&self) -> bool {
        self.differentiated
    }

    /// Whether the last factorization dropped the tangent terms (the saddle-point matrix).
    pub fn uses_kkt(&self) -> bool {
        self.uses_kkt
    }

    /// Forgets the tangent (after a failed step: the next matrix is differentiated afresh).
    pub fn invalidate(&mut self) {
        self.differentiated = false;
    }

    /// `∂r/∂q` and `∂r/∂v` at the trial state: the system's analytic tangent
    /// ([`MultibodySystem::residual_tangent`]) where every element provides one, otherwise central
    /// differences of the residual, column passes at a time. Returns the residual evaluations spent.
    pub fn differentiate(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        at: &Trial<'_>,
    ) -> u64 {
        // `mass` and `values` are left at the trial state, as the residual there left them.
        let (analytic, cost) = self.tangent.differentiate_at(system, mass, values, at);
        self.analytic = analytic;
        self.norms = (
            Self::row_sum_norm(self.tangent.pattern(), self.tangent.dr_dq(), &mut self.v),
            Self::row_sum_norm(self.tangent.pattern(), self.tangent.dr_dv(), &mut self.v),
        );
        self.differentiated = true;
        cost
    }

    /// `max_i Σ_j |values_ij|` over the tangent pattern (`sums`: scratch of `n_v`).
    fn row_sum_norm(tangent: &TangentPattern, values: &[f64], sums: &mut [f64]) -> f64 {
        sums.fill(0.0);
        for (e, (i, _)) in tangent.entries().enumerate() {
            sums[i] += values[e].abs();
        }
        sums.iter().fold(0.0, |a, &v| a.max(v))
    }

    /// Builds `[M + β' ∂r/∂q + γ' ∂r/∂v, C_qᵀ; C_q, 0]` from `mass` and `values` (which must hold
    /// the trial state: the residual there, or [`IterationMatrix::differentiate`], leaves them so)
    /// and the kept tangent, and factors it; `full` keeps the tangent terms whatever their size.
    pub fn refresh(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &BlockDiagonal,
        values: &ConstraintValues,
        (beta, gamma): (f64, f64),
        full: bool,
    ) -> Result<(), LinalgError> {
        let sys = system.constraints();
        // Drop the tangent terms when they are below `KKT_LIMIT` of the mass matrix (the Newton
        // contraction is then about that ratio) and the saddle-point factorization succeeds.
        let mut mass_norm = 0.0f64;
        for b in 0..mass.num_blocks() {
            let size = mass.size(b);
            for row in mass.block(b).chunks(size.max(1)) {
                mass_norm = mass_norm.max(row.iter().map(|v| v.abs()).sum());
            }
        }
        let ratio = (beta * self.norms.0 + gamma * self.norms.1) / mass_norm;
        if !full && ratio <= KKT_LIMIT {
            if let Some(kkt) = &mut self.kkt {
                let factored = match &mut self.reduced {
                    Some(r) => {
                        for (v, &e) in r.values.jacobian.iter_mut().zip(&r.entries) {
                            *v = values.jacobian[e];
                        }
                        kkt.factor(mass, &r.pattern, &r.values)
                    }
                    None => kkt.factor(mass, sys.pattern(), values),
                };
                if factored.is_ok() {
                    self.uses_kkt = true;
                    return Ok(());
                }
            }
        }
        self.uses_kkt = false;
        let nt = self.tangent.dr_dq().len();
        let out = self.lu.values_mut();
        let (tangent, rest) = out.split_at_mut(nt);
        for ((o, dq), dv) in tangent.iter_mut().zip(self.tangent.dr_dq()).zip(self.tangent.dr_dv()) {
            *o = beta * dq + gamma * dv;
        }
        let masked = self.reduced.as_ref().map_or(0, |r| r.dropped.len());
        let (m, rest) = rest.split_at_mut(rest.len() - 2 * values.jacobian.len() - masked);
        for (o, (_, _, v)) in m.iter_mut().zip(mass.entries()) {
            *o = v;
        }
        let (cq, rest) = rest.split_at_mut(values.jacobian.len());
        let (cqt, diagonal) = rest.split_at_mut(values.jacobian.len());
        cq.copy_from_slice(&values.jacobian);
        cqt.copy_from_slice(&values.jacobian);
        if let Some(r) = &self.reduced {
            for &e in &r.dropped_entries {
                cq[e] = 0.0;
                cqt[e] = 0.0;
            }
            diagonal.fill(1.0);
        }
        self.lu.factor()
    }

    /// `x ← A⁻¹ x` with the last factors (the masked rows of a redundant system give zero).
    pub fn solve(&mut self, system: &dyn MultibodySystem, x: &mut [f64]) {
        let n = self.v.len();
        match (&mut self.kkt, &mut self.reduced) {
            (Some(kkt), Some(r)) if self.uses_kkt => {
                r.x[..n].copy_from_slice(&x[..n]);
                for (k, &row) in r.rows.iter().enumerate() {
                    r.x[n + k] = x[n + row];
                }
                kkt.solve(&r.pattern, &mut r.x);
                x[..n].copy_from_slice(&r.x[..n]);
                for (k, &row) in r.rows.iter().enumerate() {
                    x[n + row] = r.x[n + k];
                }
                for &d in &r.dropped {
                    x[n + d] = 0.0;
                }
            }
            (Some(kkt), None) if self.uses_kkt => kkt.solve(system.constraints().pattern(), x),
            _ => self.lu.solve_in_place(x),
        }
    }

    /// The dropped equations of a redundant system (empty without redundancy).
    pub fn dropped(&self) -> &[usize] {
        self.reduced.as_ref().map_or(&[], |r| &r.dropped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::generalized_alpha::residual;
    use dalembert_testkit::generator::{build, BodySpec, LoopSpec, Spec, SpringSpec};
    use std::sync::Arc;

    /// Column-by-column central differences of the residual over all `n_v` rows (the plain method
    /// the passes replace), at the same step sizes.
    fn plain_tangent(system: &dyn MultibodySystem, at: &Trial<'_>, velocity: bool) -> Vec<Vec<f64>> {
        let n = at.v.len();
        let m = system.num_equations();
        let mut mass = system.mass_storage();
        let mut values = system.constraints().values();
        let largest = at.q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (mut plus, mut minus) = (vec![0.0; n + m], vec![0.0; n + m]);
        (0..n)
            .map(|j| {
                let size = match (velocity, at.q.len() == n) {
                    (true, _) => at.v[j].abs(),
                    (false, true) => at.q[j].abs(),
                    (false, false) => largest,
                };
                let h = 1e-7 * (1.0 + size);
                for (sign, out) in [(1.0, &mut plus), (-1.0, &mut minus)] {
                    let (mut q, mut v) = (at.q.to_vec(), at.v.to_vec());
                    if velocity {
                        v[j] += sign * h;
                    } else {
                        let mut e = vec![0.0; n];
                        e[j] = h;
                        system.integrate_positions(&mut q, &e, sign);
                    }
                    residual(
                        &mut mass,
                        &mut values,
                        system,
                        at.t,
                        (&q, &v),
                        (at.qdd, at.lambda),
                        1.0,
                        out,
                    );
                }
                (0..n).map(|i| (plus[i] - minus[i]) / (2.0 * h)).collect()
            })
            .collect()
    }

    /// The tangent from the passes equals the plain column-by-column one, and the plain one has
    /// nothing outside the declared pattern: on a planar tree with a loop and springs between
    /// bodies no joint connects (force coupling), and on spatial models (positions advanced on the
    /// rotation group, gyroscopic velocity terms). The passes change only which columns are
    /// perturbed together, and rows of one pass's columns are disjoint, so the two agree to
    /// round-off (bound 1e-10 of the largest entry).
    #[test]
    fn passes_reproduce_the_plain_tangent_on_the_declared_pattern() {
        let tree = |parent, angle: f64| BodySpec {
            parent,
            joint: 0,
            length: 1.0,
            angle,
            mass: 1.0 + angle.abs(),
            inertia_factor: 1.0,
            slide: 0.0,
        };
        let spec = Spec {
            bodies: vec![
                tree(0, -0.5),
                tree(1, -1.0),
                tree(2, 0.3),
                tree(3, -0.2),
                tree(0, -2.0),
                tree(5, 0.7),
            ],
            loops: vec![LoopSpec {
                a: 4,
                b: 6,
                kind: 1,
                at: 0.5,
            }],
            springs: vec![
                SpringSpec {
                    a: 1,
                    b: 4,
                    stiffness: 300.0,
                    damping: 7.0,
                },
                SpringSpec {
                    a: 0,
                    b: 3,
                    stiffness: 50.0,
                    damping: 2.0,
                },
            ],
            drivers: vec![],
            velocities: vec![0.4, -1.1, 0.9, 2.0, -0.3],
        };
        let planar = build(&spec).expect("mechanism");
        let spatial_chain = dalembert_testkit::spatial::chain3d(5);
        let top = dalembert_testkit::spatial::heavy_top();
        type Case = (&'static str, Arc<dyn MultibodySystem>, Vec<f64>, Vec<f64>);
        let mut cases: Vec<Case> = vec![("planar tree", planar.model.clone(), planar.q.clone(), planar.qd.clone())];
        for (name, model) in [("spatial chain", spatial_chain), ("heavy top", top)] {
            let (q, mut v) = model.initial_state();
            v.iter_mut()
                .enumerate()
                .for_each(|(i, x)| *x += 0.3 * ((i * 7) % 5) as f64 - 0.6);
            cases.push((name, model, q, v));
        }
        for (name, system, q, v) in cases {
            let (n, m) = (v.len(), system.num_equations());
            let qdd: Vec<f64> = (0..n).map(|i| ((i * 5) % 7) as f64 - 3.0).collect();
            let lambda: Vec<f64> = (0..m).map(|i| ((i * 3) % 11) as f64 - 4.0).collect();
            let at = Trial {
                t: 0.2,
                q: &q,
                v: &v,
                qdd: &qdd,
                lambda: &lambda,
            };
            let mut mass = system.mass_storage();
            system.mass(&q, &mut mass);
            let mut values = system.constraints().values();
            let mut tangent = ResidualTangent::new(&*system);
            // More than one body: some columns share a pass.
            let passes = tangent.pattern().passes().len();
            assert!(
                passes <= n && (n <= 6 || passes < n),
                "{name}: {passes} passes for {n} columns"
            );
            tangent.differences(&*system, &mut mass, &mut values, &at);
            for (velocity, got) in [(false, tangent.dr_dq()), (true, tangent.dr_dv())] {
                let plain = plain_tangent(&*system, &at, velocity);
                let scale = plain.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
                assert!(scale > 0.0, "{name}");
                let mut dense = vec![vec![0.0; n]; n];
                for (e, (i, j)) in tangent.pattern().entries().enumerate() {
                    dense[j][i] = got[e];
                }
                for j in 0..n {
                    for i in 0..n {
                        let d = (dense[j][i] - plain[j][i]).abs();
                        assert!(
                            d <= 1e-10 * scale,
                            "{name}, {}: entry ({i}, {j}) {} from the passes, {} plain",
                            if velocity { "∂r/∂v" } else { "∂r/∂q" },
                            dense[j][i],
                            plain[j][i]
                        );
                    }
                }
            }
        }
    }

    /// Compares the analytic tangent of `system` at a state with column-by-column central
    /// differences of the residual; returns the worst difference relative to the largest entry.
    fn analytic_error(system: &dyn MultibodySystem, q: &[f64], v: &[f64], seed: usize) -> f64 {
        let (n, m) = (v.len(), system.num_equations());
        let qdd: Vec<f64> = (0..n).map(|i| ((i * 5 + seed) % 7) as f64 - 3.0).collect();
        let lambda: Vec<f64> = (0..m).map(|i| 10.0 * (((i * 3 + seed) % 11) as f64 - 4.0)).collect();
        let at = Trial {
            t: 0.2,
            q,
            v,
            qdd: &qdd,
            lambda: &lambda,
        };
        let mut mass = system.mass_storage();
        system.mass(q, &mut mass);
        let mut values = system.constraints().values();
        let mut matrix = IterationMatrix::new(system, &mass, None).unwrap();
        assert_eq!(matrix.differentiate(system, &mut mass, &mut values, &at), 0);
        assert!(matrix.is_analytic());
        let mut worst = 0.0f64;
        for (velocity, got) in [(false, matrix.tangent.dr_dq()), (true, matrix.tangent.dr_dv())] {
            let plain = plain_tangent(system, &at, velocity);
            let scale = plain.iter().flatten().fold(1.0f64, |a, v| a.max(v.abs()));
            let mut dense = vec![vec![0.0; n]; n];
            for (e, (i, j)) in matrix.tangent.pattern().entries().enumerate() {
                dense[j][i] = got[e];
            }
            for j in 0..n {
                for i in 0..n {
                    worst = worst.max((dense[j][i] - plain[j][i]).abs() / scale);
                }
            }
        }
        worst
    }

    /// The planar analytic tangent (constraint second derivatives weighted by `λ`, force-element
    /// Jacobians) equals column-by-column central differences of the residual on 60 generated
    /// mechanisms (revolute, prismatic and distance joints; revolute, distance and point-on-line
    /// loops; angle drivers; spring–dampers) at random consistent states, with multipliers up to
    /// 60 so that the constraint terms dominate. Bound 1e-6 of the largest entry: the differences'
    /// truncation (`h² ≈ 1e-14` relative) and round-off (`ε |r| / h ≈ 1e-9`) lie far below, a wrong
    /// term is O(1). Spatial models are analytic too: a chain, the heavy top, the slider-crank and a
    /// double pendulum with every force element.
    #[test]
    fn analytic_tangent_matches_differences() {
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut tested = 0;
        for case in 0..60 {
            let nb = 1 + (next() * 6.0) as usize;
            let bodies = (0..nb)
                .map(|_| BodySpec {
                    parent: (next() * 8.0) as usize,
                    joint: (next() * 3.0) as u8,
                    length: 0.3 + 1.7 * next(),
                    angle: -3.0 + 6.0 * next(),
                    mass: 10f64.powf(-1.0 + 2.0 * next()),
                    inertia_factor: 0.2 + 1.8 * next(),
                    slide: -0.5 + next(),
                })
                .collect();
            let loops = (0..(next() * 3.0) as usize)
                .map(|_| LoopSpec {
                    a: (next() * 8.0) as usize,
                    b: (next() * 8.0) as usize,
                    kind: (next() * 3.0) as u8,
                    at: next(),
                })
                .collect();
            let springs = (0..(next() * 3.0) as usize)
                .map(|_| SpringSpec {
                    a: (next() * 8.0) as usize,
                    b: (next() * 8.0) as usize,
                    stiffness: 1.0 + 499.0 * next(),
                    damping: 5.0 * next(),
                })
                .collect();
            let drivers = (0..(next() * 2.0) as usize).map(|_| (next() * 6.0) as usize).collect();
            let velocities = (0..5).map(|_| -3.0 + 6.0 * next()).collect();
            let spec = Spec {
                bodies,
                loops,
                springs,
                drivers,
                velocities,
            };
            let Some(mech) = build(&spec) else { continue };
            let err = analytic_error(&*mech.model, &mech.q, &mech.qd, case);
            assert!(
                err <= 1e-6,
                "case {case}: analytic tangent {err:.2e} off the differences, {spec:?}"
            );
            tested += 1;
        }
        assert!(tested >= 40, "only {tested} mechanisms built");
        // Spatial models (a rotation perturbation is along the body-frame angular velocity, as the
        // differences take it), at states with velocities on every coordinate.
        for (name, model) in [
            (
                "spatial pendulum with every force element",
                dalembert_testkit::spatial::forced_double_pendulum(),
            ),
            ("spatial chain", dalembert_testkit::spatial::chain3d(5)),
            ("heavy top", dalembert_testkit::spatial::heavy_top()),
            ("spatial slider-crank", dalembert_testkit::spatial::slider_crank_3d()),
        ] {
            let (q, mut v) = model.initial_state();
            v.iter_mut()
                .enumerate()
                .for_each(|(i, x)| *x += 0.4 * ((i * 7) % 5) as f64 - 0.8);
            let err = analytic_error(&*model, &q, &v, 3);
            assert!(err <= 1e-6, "{name}: analytic tangent {err:.2e} off the differences");
        }
    }
}
