//! A run in joint coordinates seen in the model's absolute coordinates: [`JointMap`].
//!
//! A spatial tree integrated in joint coordinates ([`Coordinates::Joint`]) reports every sample in
//! the model's own coordinates: the joint state mapped to each body's centre of mass, Euler
//! parameters and velocities, then `q̈`, `λ` (hence the reactions) and the constraint residuals of
//! the model's own formulation there, one evaluation per sample. [`crate::Simulation::run`] and the
//! [`crate::Simulator`] share this map.
//!
//! [`Coordinates::Joint`]: crate::Coordinates::Joint

use crate::simulation::{Simulation, SimulationError};
use dalembert_integrators::Sample;
use dalembert_spatial::JointCoordinates;
use dalembert_system::tree::WorldFrame;
use dalembert_system::{DynamicsError, Formulation, ModelError};

/// The map from a joint-coordinate run to the model's coordinates, with its storage
/// (allocation-free after construction).
pub(crate) struct JointMap {
    jc: JointCoordinates,
    /// The chosen formulation on the model's absolute coordinates (for `q̈`, `λ`, residuals),
    /// without the switching law: the run's friction and limit forces are added to it.
    absolute: Box<dyn Formulation>,
    /// The run's friction and limit forces as one generalized force of the model, and one
    /// element's row.
    extra: Vec<f64>,
    row: dalembert_system::SlipRow,
    frames: Vec<WorldFrame>,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    c: Vec<f64>,
    cdot: Vec<f64>,
}

/// A joint-coordinate run's start: the map, the formulation on the joint coordinates and the
/// initial joint state.
pub(crate) struct JointStart {
    pub map: JointMap,
    pub formulation: Box<dyn Formulation>,
    pub q0: Vec<f64>,
    pub qd0: Vec<f64>,
}

impl JointMap {
    /// The tree of `simulation`'s spatial model with its zero configuration at the absolute
    /// (assembled) state `(q, q̇)`, the chosen formulation on it and on the model.
    pub fn start(simulation: &Simulation, q: &[f64], qd: &[f64]) -> Result<JointStart, SimulationError> {
        let model = simulation.model.spatial().ok_or_else(|| {
            SimulationError::JointCoordinates(ModelError::InvalidParameter {
                element: "model".into(),
                what: "joint coordinates are for spatial models".into(),
            })
        })?;
        let jc = model
            .joint_coordinates_at(q, qd)
            .map_err(SimulationError::JointCoordinates)?;
        let (q0, qd0) = jc.initial_state();
        // The model's independent coordinates do not index the joint coordinates (which are all
        // independent).
        let formulation = simulation.formulation_on(jc.system(), None)?;
        let absolute = simulation.formulation_without_switching()?;
        let (n, m) = (qd.len(), simulation.model.num_equations());
        let map = JointMap {
            frames: jc.frames(),
            jc,
            absolute,
            q: q.to_vec(),
            qd: qd.to_vec(),
            qdd: vec![0.0; n],
            extra: vec![0.0; n],
            row: dalembert_system::SlipRow::default(),
            lambda: vec![0.0; m],
            c: vec![0.0; m],
            cdot: vec![0.0; m],
        };
        Ok(JointStart {
            map,
            formulation,
            q0,
            qd0,
        })
    }

    /// Maps the joint state `(q, q̇)` to the model's coordinates ([`JointMap::state`]).
    pub fn map(&mut self, q: &[f64], qd: &[f64]) {
        self.jc.absolute(q, qd, &mut self.frames, &mut self.q, &mut self.qd);
    }

    /// The model's state last mapped.
    pub fn state(&self) -> (&[f64], &[f64]) {
        (&self.q, &self.qd)
    }

    /// Sample `s` of the joint-coordinate run in the model's coordinates: the state mapped, `q̈`,
    /// `λ` and the residuals evaluated there by the model's formulation with the run's friction
    /// and limit forces added (each along its element's row in the model's coordinates, whose
    /// rate is the same joint rate, so the same force); the energy, the friction and limit forces
    /// and the energy the impacts took are the run's (the same mechanism's).
    pub fn sample<'a>(&'a mut self, s: &Sample<'a>) -> Result<Sample<'a>, DynamicsError> {
        self.map(s.q, s.qd);
        let limited = s.limit.iter().chain(s.friction).any(|f| *f != 0.0);
        if limited {
            self.extra.iter_mut().for_each(|x| *x = 0.0);
            let model = self.absolute.system();
            for (k, f) in s.limit.iter().enumerate() {
                model.limit_row(k, s.t, &self.q, &self.qd, &mut self.row);
                for &(i, g) in self.row.entries() {
                    self.extra[i] += g * f;
                }
            }
            for (k, f) in s.friction.iter().enumerate() {
                model.slip_row(k, s.t, &self.q, &self.qd, &mut self.row);
                for &(i, g) in self.row.entries() {
                    self.extra[i] += g * f;
                }
            }
            self.absolute.set_extra_force(Some(&self.extra));
        }
        let solved = self
            .absolute
            .accelerations(s.t, &self.q, &self.qd, None, &mut self.qdd, &mut self.lambda);
        if limited {
            self.absolute.set_extra_force(None);
        }
        solved?;
        self.absolute
            .residuals(s.t, &self.q, &self.qd, &mut self.c, &mut self.cdot);
        let max = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        Ok(Sample {
            t: s.t,
            q: &self.q,
            qd: &self.qd,
            qdd: &self.qdd,
            lambda: &self.lambda,
            friction: s.friction,
            limit: s.limit,
            impact_loss: s.impact_loss,
            work: s.work,
            constraint_violation: max(&self.c),
            velocity_violation: max(&self.cdot),
            energy: s.energy,
        })
    }
}
