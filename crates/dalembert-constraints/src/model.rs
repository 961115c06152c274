//! A complete multibody model: bodies, applied forces and constraints.

use crate::{Constraint, ConstraintError, ConstraintSystem};
use dalembert_kinematics::{Body, ForceElement, MassMatrix};

/// Bodies, applied force elements and the assembled constraint system of one mechanism.
#[derive(Debug)]
pub struct Model {
    bodies: Vec<Body>,
    forces: Vec<Box<dyn ForceElement>>,
    constraints: ConstraintSystem,
}

impl Model {
    /// Validates and assembles a model. Errors name the element at fault.
    pub fn new(
        bodies: Vec<Body>,
        forces: Vec<Box<dyn ForceElement>>,
        constraints: Vec<Box<dyn Constraint>>,
    ) -> Result<Self, ConstraintError> {
        for f in &forces {
            f.validate(bodies.len())?;
        }
        let constraints = ConstraintSystem::new(bodies.len(), constraints)?;
        Ok(Model {
            bodies,
            forces,
            constraints,
        })
    }

    /// The moving bodies, in coordinate order.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The applied force elements.
    pub fn forces(&self) -> &[Box<dyn ForceElement>] {
        &self.forces
    }

    /// The constraint system.
    pub fn constraints(&self) -> &ConstraintSystem {
        &self.constraints
    }

    /// Number of coordinates `n`.
    pub fn num_coordinates(&self) -> usize {
        3 * self.bodies.len()
    }

    /// Number of constraint equations `m`.
    pub fn num_equations(&self) -> usize {
        self.constraints.num_equations()
    }

    /// The mass matrix at `q`.
    pub fn mass_matrix(&self, q: &[f64]) -> MassMatrix {
        MassMatrix::new(&self.bodies, q)
    }

    /// `Q_e`: all applied generalized forces plus the quadratic-velocity force of offset centres of
    /// mass, written (not added) into `q_e`. Allocates nothing.
    pub fn applied_forces(&self, t: f64, q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        q_e.iter_mut().for_each(|x| *x = 0.0);
        for f in &self.forces {
            f.add_generalized_force(t, &self.bodies, q, qd, q_e);
        }
        MassMatrix::add_quadratic_velocity_force(&self.bodies, q, qd, q_e);
    }

    /// `Ok` when the applied forces `q_e` (from [`Model::applied_forces`] at `(t, q, q̇)`) are
    /// finite; otherwise the error names the force element whose generalized force overflows or is
    /// not a number (found by evaluating each element alone: only on this failure path).
    pub fn check_forces(&self, t: f64, q: &[f64], qd: &[f64], q_e: &[f64]) -> Result<(), crate::DynamicsError> {
        if q_e.iter().all(|x| x.is_finite()) {
            return Ok(());
        }
        let mut one = vec![0.0; q_e.len()];
        let what = self
            .forces
            .iter()
            .find(|f| {
                one.iter_mut().for_each(|x| *x = 0.0);
                f.add_generalized_force(t, &self.bodies, q, qd, &mut one);
                one.iter().any(|x| !x.is_finite())
            })
            .map_or_else(
                || "quadratic-velocity force of an offset centre of mass (velocities overflow)".to_string(),
                |f| {
                    format!(
                        "or overflowing generalized force of '{}' (check its parameters and the state)",
                        f.name()
                    )
                },
            );
        Err(crate::DynamicsError::NonFinite { time: t, what })
    }

    /// True when `T + V` is a first integral of the exact motion: every force element is
    /// conservative and no constraint is driven (a driver does work).
    pub fn is_conservative(&self) -> bool {
        self.forces.iter().all(|f| f.is_conservative())
            && self
                .constraints
                .constraints()
                .iter()
                .all(|c| c.role() != crate::ConstraintRole::Driver)
    }

    /// Total potential energy of the conservative elements at `(t, q)`.
    pub fn potential_energy(&self, t: f64, q: &[f64]) -> f64 {
        self.forces
            .iter()
            .filter_map(|f| f.potential_energy(t, &self.bodies, q))
            .sum()
    }

    /// The error for a singular system whose cause is not a rank-deficient `C_q`: `SingularMass`
    /// naming the bodies without mass or inertia when there are any, otherwise `Singular` with `what`.
    pub fn singular_mass_error(&self, t: f64, what: &str) -> crate::DynamicsError {
        let bodies: Vec<String> = self
            .bodies
            .iter()
            .filter(|b| b.mass == 0.0 || b.inertia_about_reference() == 0.0)
            .map(|b| b.name.clone())
            .collect();
        if bodies.is_empty() {
            crate::DynamicsError::Singular {
                time: t,
                what: what.to_string(),
            }
        } else {
            crate::DynamicsError::SingularMass { time: t, bodies }
        }
    }

    /// `Ok` when every position and velocity is finite; otherwise the error names the body and the
    /// coordinate.
    pub fn check_state(&self, t: f64, q: &[f64], qd: &[f64]) -> Result<(), crate::DynamicsError> {
        self.check_lengths(&[("q", q.len()), ("q̇", qd.len())], &[])?;
        for (v, what) in [(q, "position"), (qd, "velocity")] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                let coord = ["x", "y", "angle"][i % 3];
                let body = &self.bodies[i / 3].name;
                return Err(crate::DynamicsError::NonFinite {
                    time: t,
                    what: format!("{what} {coord} of body '{body}'"),
                });
            }
        }
        Ok(())
    }

    /// `Ok` when every coordinate-sized slice (`(name, length)` in `coordinates`) has `n` entries
    /// and every equation-sized one (`equations`) has `m`; otherwise the error names the first
    /// slice that does not (a caller's mistake reported instead of an index panic).
    pub fn check_lengths(
        &self,
        coordinates: &[(&'static str, usize)],
        equations: &[(&'static str, usize)],
    ) -> Result<(), crate::DynamicsError> {
        let (n, m) = (self.num_coordinates(), self.num_equations());
        let wrong = coordinates
            .iter()
            .map(|&(w, l)| (w, l, n))
            .chain(equations.iter().map(|&(w, l)| (w, l, m)))
            .find(|&(_, l, e)| l != e);
        match wrong {
            None => Ok(()),
            Some((what, got, expected)) => Err(crate::DynamicsError::WrongLength { what, expected, got }),
        }
    }

    /// Kinetic energy `½ q̇ᵀ M q̇`, computed body by body without building `M` (no trigonometry
    /// for bodies whose reference point is the centre of mass).
    pub fn kinetic_energy(&self, q: &[f64], qd: &[f64]) -> f64 {
        self.bodies
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let v = nalgebra::Vector3::new(qd[3 * i], qd[3 * i + 1], qd[3 * i + 2]);
                if b.center_of_mass == dalembert_kinematics::Vec2::zeros() {
                    0.5 * (b.mass * (v.x * v.x + v.y * v.y) + b.inertia * v.z * v.z)
                } else {
                    let blk = MassMatrix::block(b, q[3 * i + 2]);
                    0.5 * v.dot(&(blk * v))
                }
            })
            .sum()
    }
}
