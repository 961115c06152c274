//! Where a scene comes to rest: its motion with kinetic damping (`settled`), the start that
//! [`crate::Scene::equilibrium`] takes when Newton's method from the scene's own position ends at
//! an unstable equilibrium or at none.
//!
//! The scene's motion (its own formulation; Dormand–Prince at tolerances 1e-4 with projection) is
//! stepped; each time the kinetic
//! energy passes a peak, the velocities are set to zero there (kinetic damping: the state then
//! holds the least potential energy along that swing). The energy removed falls toward a minimum
//! of the potential, a stable equilibrium, and never toward a maximum. Stops when a peak's kinetic
//! energy is below `1e-10` of the energy removed so far (at rest to that share), or after
//! [`MAX_STEPS`]. Drivers would move with time, so a driven model is not relaxed.

use crate::Scene;

/// The most steps a relaxation takes.
pub const MAX_STEPS: usize = 50_000;

/// The relative and absolute tolerances of the relaxation's Dormand–Prince steps.
pub const RELAXATION_TOLERANCE: f64 = 1e-4;

/// The positions where `scene`'s motion with kinetic damping comes to rest, or `None` when it
/// cannot be run (a driven model, a failed step).
pub(crate) fn settled(scene: &Scene) -> Option<Vec<f64>> {
    if !scene.model.kind().driver_names().is_empty() {
        return None;
    }
    let system = scene.model.as_system();
    // The scene's formulation, with Dormand–Prince at loose tolerances and projection: only the
    // way down matters, not its accuracy, and the adaptive step grows to what stability allows.
    let mut relaxing = scene.clone();
    let settings = &mut relaxing.settings;
    settings.method = dalembert_integrators::Method::dopri5(RELAXATION_TOLERANCE, RELAXATION_TOLERANCE);
    settings.stabilization = dalembert_integrators::Stabilization::projection();
    let mut sim = relaxing.simulator().ok()?;
    let zero = vec![0.0; scene.qd.len()];
    let (mut rising, mut last) = (false, 0.0f64);
    let mut removed = 0.0f64;
    for _ in 0..MAX_STEPS {
        sim.step().ok()?;
        let (q, qd) = sim.state();
        let kinetic = system.kinetic_energy(q, qd);
        if kinetic < last && rising {
            // Past a peak: stop the motion here.
            removed += last;
            let q = q.to_vec();
            sim.set_state(&q, &zero).ok()?;
            if last <= 1e-10 * removed {
                return Some(q);
            }
            (rising, last) = (false, 0.0);
            continue;
        }
        rising = kinetic > last;
        last = kinetic;
    }
    Some(sim.state().0.to_vec())
}
