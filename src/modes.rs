//! Vibration modes about a static equilibrium: [`Scene::modes`].
//!
//! At the equilibrium ([`Scene::equilibrium`]) the motion linearized in the independent
//! coordinates `v_i` of coordinate partitioning is `M_r δq̈_i + D_r δq̇_i + K_r δq_i = 0`, with
//! `M_r = Bᵀ M B`, `D_r = Bᵀ (∂r/∂v) B`, `K_r = Bᵀ (∂r/∂q) B` (`docs/statics.md`, equations
//! S4–S6). The natural frequencies and the mode shapes are those of the undamped problem
//! `K_r φ = ω² M_r φ` (a symmetric definite eigenproblem through the Cholesky factor of `M_r`);
//! with damping, the frequencies and damping ratios are those of the eigenvalues `s` of the first
//! order system, `ω_n = |s|`, `ζ = −Re s / |s|` (an overdamped pair of real eigenvalues
//! `s₁ s₂`: `ω_n = √(s₁ s₂)`, `ζ = −(s₁ + s₂) / (2 ω_n)`), and the shapes stay the undamped ones.

use crate::animation::Frames;
use crate::equilibrium::{relative_stiffness, Equilibrium, EquilibriumError};
use crate::Scene;
use nalgebra::DMatrix;
use std::f64::consts::PI;

/// The vibration modes of a scene about its equilibrium.
#[derive(Debug, Clone, PartialEq)]
pub struct Modes {
    /// Natural frequencies in Hz, ascending (`ω_n / 2π`).
    pub frequencies: Vec<f64>,
    /// Damping ratio of each mode (0 without damping; above 1 overdamped).
    pub damping_ratios: Vec<f64>,
    /// The position columns the shapes are given over (`crank.x`, …, `top.e3`).
    pub columns: Vec<String>,
    /// One shape per mode over [`Modes::columns`]: the change of the positions along the mode,
    /// scaled to a largest component of 1 (positive).
    pub shapes: Vec<Vec<f64>>,
    /// The same shapes in the velocity coordinates (`B φ`, one per mode, the model's `n_v`
    /// numbers), scaled alike: the direction [`Scene::mode_frames`] moves the positions along.
    pub velocity_shapes: Vec<Vec<f64>>,
    /// The equilibrium the modes are about.
    pub equilibrium: Equilibrium,
}

impl Scene {
    /// The vibration modes about the equilibrium nearest the scene's position (see the module
    /// documentation). A neutral direction ([`Equilibrium::free_directions`]) is a mode of 0 Hz;
    /// an unstable equilibrium is refused (its "frequencies" would be growth rates).
    pub fn modes(&self) -> Result<Modes, EquilibriumError> {
        if let Some(f) = self.model.system().frictions().first() {
            return Err(EquilibriumError::Model(format!(
                "{} '{}' has Coulomb friction: small vibrations with it are not linear, so it has no modes",
                f.element, f.name
            )));
        }
        // Limits: the equilibrium is refused where one is reached; small vibrations about it
        // stay clear of the bounds.
        let equilibrium = self.equilibrium()?;
        if !equilibrium.unstable_directions.is_empty() {
            return Err(EquilibriumError::Model(format!(
                "the equilibrium found from the scene's position is unstable along {}: it has no vibration modes (start the scene nearer a stable one)",
                equilibrium.unstable_directions.join("; ")
            )));
        }
        let system = self.model.as_system();
        // The reduced matrices the equilibrium was judged with (the same state and multipliers).
        let r = equilibrium.reduced.clone();
        let dof = r.m.nrows();
        if dof == 0 {
            // Nothing moves: a fully driven or fully constrained model has no modes.
            return Ok(Modes {
                frequencies: Vec::new(),
                damping_ratios: Vec::new(),
                columns: equilibrium.positions.iter().map(|(c, _)| c.clone()).collect(),
                shapes: Vec::new(),
                velocity_shapes: Vec::new(),
                equilibrium,
            });
        }
        let m = (&r.m + r.m.transpose()) * 0.5;
        let k = (&r.k + r.k.transpose()) * 0.5;
        if m.clone().cholesky().is_none() {
            return Err(EquilibriumError::Model(
                "the mass matrix is singular on the admissible motions (a body without mass or inertia moves)".into(),
            ));
        }
        // The undamped problem K_r φ = ω² M_r φ: its eigenvalues ascending and the velocities B φ.
        let (squares, velocities) = relative_stiffness(&r);
        let (frequencies, damping_ratios) = if r.d.iter().all(|&x| x == 0.0) {
            let f = squares.iter().map(|w2| w2.max(0.0).sqrt() / (2.0 * PI)).collect();
            (f, vec![0.0; dof])
        } else {
            damped(&m, &r.d, &k)?
        };
        // Shapes: the positions' change T(q) B φ, scaled to a largest component of 1.
        let n_q = system.layout().n_q();
        let columns: Vec<String> = equilibrium.positions.iter().map(|(c, _)| c.clone()).collect();
        let mut shapes = Vec::with_capacity(dof);
        let mut velocity_shapes = Vec::with_capacity(dof);
        for v in &velocities {
            let mut dq = vec![0.0; n_q];
            system.position_rates(&equilibrium.q, v, &mut dq);
            let (largest, at) =
                dq.iter().enumerate().fold(
                    (0.0f64, 0),
                    |(a, k), (j, x)| if x.abs() > a { (x.abs(), j) } else { (a, k) },
                );
            let scale = if largest > 0.0 { dq[at].signum() / largest } else { 1.0 };
            shapes.push(dq.iter().map(|x| x * scale).collect());
            velocity_shapes.push(v.iter().map(|x| x * scale).collect());
        }
        Ok(Modes {
            frequencies,
            damping_ratios,
            columns,
            shapes,
            velocity_shapes,
            equilibrium,
        })
    }

    /// Frames of mode `k` (0-based, as in [`Modes::frequencies`]) for the viewer: the positions
    /// `q_eq ⊕ a sin(2π f t) B φ` assembled to the constraints (the least change), over
    /// `cycles` periods at 48 frames each (a mode of 0 Hz over `cycles` seconds). The amplitude
    /// `a` moves no centre of mass by more than a tenth of the model's size (its largest
    /// translational coordinate at the equilibrium) and turns no body by more than 0.3 rad.
    pub fn mode_frames(&self, modes: &Modes, k: usize, cycles: usize) -> Result<Frames, EquilibriumError> {
        let Some(shape) = modes.velocity_shapes.get(k) else {
            return Err(EquilibriumError::Model(format!(
                "mode {} asked for: the scene has {} mode(s)",
                k + 1,
                modes.velocity_shapes.len()
            )));
        };
        let system = self.model.as_system();
        let q0 = &modes.equilibrium.q;
        // The model's size: its largest translational coordinate at the equilibrium.
        let mut size = 0.0f64;
        for b in system.layout().bodies() {
            for (k, label) in b.q_labels.iter().enumerate() {
                if matches!(*label, "x" | "y" | "z") {
                    size = size.max(q0[b.q_offset + k].abs());
                }
            }
        }
        let size = if size > 0.0 { size } else { 1.0 };
        // Per velocity coordinate: a rotation (angle, angular velocity) or a translation.
        let rotation: Vec<bool> = (system.layout().bodies().iter())
            .flat_map(|b| b.v_labels.iter().map(|l| *l == "angle" || l.starts_with('w')))
            .collect();
        let largest = |keep: bool| {
            shape
                .iter()
                .zip(&rotation)
                .filter(|(_, &r)| r == keep)
                .fold(0.0f64, |a, (x, _)| a.max(x.abs()))
        };
        let mut amplitude = f64::INFINITY;
        if largest(false) > 0.0 {
            amplitude = amplitude.min(0.1 * size / largest(false));
        }
        if largest(true) > 0.0 {
            amplitude = amplitude.min(0.3 / largest(true));
        }
        if !amplitude.is_finite() {
            amplitude = 0.0;
        }
        let f = modes.frequencies[k];
        let period = if f > 0.0 { 1.0 / f } else { 1.0 };
        let count = 48 * cycles.max(1);
        let mut frames = Frames::for_drawing(&self.drawing);
        let (sys, opts) = (system.constraints(), dalembert_system::KinematicOptions::default());
        let mut q = q0.clone();
        for i in 0..=count {
            let t = period * i as f64 / 48.0;
            q.copy_from_slice(q0);
            system.integrate_positions(&mut q, shape, amplitude * (2.0 * PI * t / period).sin());
            system.normalize(&mut q);
            sys.solve_positions(0.0, &mut q, &opts)
                .map_err(|e| EquilibriumError::Model(format!("mode {} cannot be drawn at t = {t}: {e}", k + 1)))?;
            frames.push(t, &q);
        }
        Ok(frames)
    }
}

/// Natural frequencies (Hz) and damping ratios from the eigenvalues of the first-order system
/// `[0 I; −M⁻¹K −M⁻¹D]`, ascending in frequency.
fn damped(m: &DMatrix<f64>, d: &DMatrix<f64>, k: &DMatrix<f64>) -> Result<(Vec<f64>, Vec<f64>), EquilibriumError> {
    let dof = m.nrows();
    let m_inv = m.clone().try_inverse().ok_or_else(|| {
        EquilibriumError::Model("the mass matrix on the admissible motions cannot be inverted".into())
    })?;
    let mut a = DMatrix::<f64>::zeros(2 * dof, 2 * dof);
    for i in 0..dof {
        a[(i, dof + i)] = 1.0;
    }
    let mk = -(&m_inv * k);
    let md = -(&m_inv * d);
    for i in 0..dof {
        for j in 0..dof {
            a[(dof + i, j)] = mk[(i, j)];
            a[(dof + i, dof + j)] = md[(i, j)];
        }
    }
    let s = a.complex_eigenvalues();
    let scale = s.iter().fold(0.0f64, |x, z| x.max(z.norm()));
    let tol = 1e-10 * scale.max(f64::MIN_POSITIVE);
    let mut modes: Vec<(f64, f64)> = s
        .iter()
        .filter(|z| z.im > tol)
        .map(|z| {
            let w = z.norm();
            (w, -z.re / w)
        })
        .collect();
    let mut reals: Vec<f64> = s.iter().filter(|z| z.im.abs() <= tol).map(|z| z.re).collect();
    reals.sort_by(|a, b| b.total_cmp(a)); // nearest zero first
    for pair in reals.chunks(2) {
        if let [s1, s2] = *pair {
            let w = (s1 * s2).max(0.0).sqrt();
            modes.push((w, if w > 0.0 { -(s1 + s2) / (2.0 * w) } else { f64::INFINITY }));
        }
    }
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok((
        modes.iter().map(|(w, _)| w / (2.0 * PI)).collect(),
        modes.iter().map(|&(_, z)| z).collect(),
    ))
}
