//! Where a scene comes to rest: its motion with kinetic damping (`Relaxation`), the start that
//! [`crate::Scene::equilibrium`] takes when Newton's method from the scene's own position ends at
//! an unstable equilibrium or at none.
//!
//! The scene's motion (in joint coordinates where the model allows them, else its own formulation
//! with projection; Dormand–Prince at tolerances 1e-4) is stepped; each time the kinetic
//! energy passes a peak, the velocities are set to zero there (kinetic damping: the state then
//! holds the least potential energy along that swing). The energy removed falls toward a minimum
//! of the potential, a stable equilibrium, and never toward a maximum. `Relaxation::until`
//! stops when a peak's kinetic energy is below a share of the energy removed so far (at rest to
//! that share, [`SHARES`]), or after [`MAX_STEPS`] in all, and goes on from there when asked for a
//! smaller share. Drivers would move with time, so a driven model is not relaxed.

use crate::Scene;

/// The most steps a relaxation takes.
pub const MAX_STEPS: usize = 50_000;

/// The share of the energy removed below which the kinetic energy counts as none at all: the
/// motion has stopped (held against a stop, or balanced) and no peak will come. Far below every
/// share of [`SHARES`]; right after the velocities are set to zero, the next step's kinetic
/// energy is of the order of `(F h)² / m`, far above it unless the forces balance.
pub const AT_REST: f64 = 1e-20;

/// The relative and absolute tolerances of the relaxation's Dormand–Prince steps.
pub const RELAXATION_TOLERANCE: f64 = 1e-4;

/// The shares of the energy removed so far below which a peak's kinetic energy lets
/// [`crate::Scene::equilibrium`] try Newton's method from the relaxed positions, in turn: a
/// loosely relaxed start usually lies in the stable equilibrium's basin already, and only where
/// Newton's method still ends at an unstable one does the relaxation go on to the next share
/// (the last, `1e-10`, at rest to round-off of the energy).
pub const SHARES: [f64; 4] = [1e-2, 1e-4, 1e-7, 1e-10];

/// A scene's motion with kinetic damping, stepped until it comes to rest to a share of the
/// energy it lost ([`Relaxation::until`]), and resumed from there for a smaller share.
pub(crate) struct Relaxation<'a> {
    sim: crate::Simulator,
    system: &'a dyn dalembert_system::MultibodySystem,
    rising: bool,
    last: f64,
    removed: f64,
    steps: usize,
}

impl<'a> Relaxation<'a> {
    /// The relaxation of `scene`, or `None` when it cannot be run (a driven model).
    pub(crate) fn new(scene: &'a Scene) -> Option<Self> {
        if !scene.model.kind().driver_names().is_empty() {
            return None;
        }
        // The scene's formulation, with Dormand–Prince at loose tolerances and projection: only
        // the way down matters, not its accuracy, and the adaptive step grows to what stability
        // allows. A spatial tree runs in joint coordinates where it can (the articulated-body
        // algorithm: on a chain of 64 links it relaxes in 89 ms where absolute coordinates take
        // 353 ms; the joints hold by construction, and the driver projects nothing where there
        // are no constraint equations).
        let mut relaxing = scene.clone();
        let settings = &mut relaxing.settings;
        settings.method = dalembert_integrators::Method::dopri5(RELAXATION_TOLERANCE, RELAXATION_TOLERANCE);
        settings.stabilization = dalembert_integrators::Stabilization::projection();
        let mut joint = relaxing.clone();
        joint.settings.coordinates = crate::simulation::Coordinates::Joint;
        let sim = match joint.simulator() {
            Ok(sim) => sim,
            Err(_) => relaxing.simulator().ok()?,
        };
        Some(Relaxation {
            sim,
            system: scene.model.as_system(),
            rising: false,
            last: 0.0,
            removed: 0.0,
            steps: 0,
        })
    }

    /// Steps on until a peak's kinetic energy is below `share` of the energy removed so far, and
    /// returns the positions there (those reached after [`MAX_STEPS`] in all); `None` when a step
    /// fails.
    pub(crate) fn until(&mut self, share: f64) -> Option<Vec<f64>> {
        while self.steps < MAX_STEPS {
            self.steps += 1;
            self.sim.step().ok()?;
            let (q, qd) = self.sim.state();
            let kinetic = self.system.kinetic_energy(q, qd);
            if kinetic <= AT_REST * self.removed {
                // At rest (against a stop, or balanced): no peak is coming.
                return Some(q.to_vec());
            }
            if kinetic < self.last && self.rising {
                // Past a peak: stop the motion here.
                self.removed += self.last;
                let q = q.to_vec();
                self.sim.stop_motion().ok()?;
                let at_rest = self.last <= share * self.removed;
                (self.rising, self.last) = (false, 0.0);
                if at_rest {
                    return Some(q);
                }
                continue;
            }
            self.rising = kinetic > self.last;
            self.last = kinetic;
        }
        Some(self.sim.state().0.to_vec())
    }
}
