//! The locomotion task (paper §IV): keep the largest body, settle it on the floor under gravity,
//! record the centre of mass, actuate for a number of cycles, and score the centre of mass's
//! displacement along +X.

use serde::{Deserialize, Serialize};

use super::math::Vec3;
use super::scene::{DynamicScene, LocomotionFitness};
use super::simulation::{DivergenceReason, Simulation};
use crate::material::Palette;
use crate::voxel::{VoxelGrid, keep_largest_component};

/// How a locomotion evaluation ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum LocomotionStatus {
    /// Settled and actuated for every cycle; the fitness is meaningful.
    Completed,
    /// Stopped at `time` (s) for `reason`; the fitness is 0.
    Diverged { reason: DivergenceReason, time: f64 },
    /// The design has no voxels.
    Empty,
    /// The scene or palette is invalid (the message names the field).
    Invalid { message: String },
}

/// The result of [`simulate_locomotion`]. Every number is finite.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocomotionOutcome {
    pub status: LocomotionStatus,
    /// Travel of the centre of mass along +X as the scene's [`LocomotionFitness`] measures it, m
    /// (0 unless completed).
    pub fitness: f64,
    /// Displacement of the centre of mass along +X from the end of settling to the end of the
    /// last actuation cycle, m (0 unless completed).
    pub displacement: f64,
    /// fitness / body length / cycles, in % of body length per cycle (paper's Table IV measure).
    pub speed_percent_per_cycle: f64,
    /// Extent of the body along X at rest, m.
    pub body_length: f64,
    pub voxel_count: usize,
    pub steps: u64,
    /// Simulated time, s (settling plus actuation).
    pub simulated_time: f64,
    /// How long settling took, s.
    pub settle_time: f64,
    /// Time step used, s.
    pub dt: f64,
    /// Centre of mass at the end of settling and after each actuation cycle, m.
    pub centre_of_mass_trace: Vec<[f64; 3]>,
}

impl LocomotionOutcome {
    fn failed(status: LocomotionStatus, voxel_count: usize) -> Self {
        Self {
            status,
            fitness: 0.0,
            displacement: 0.0,
            speed_percent_per_cycle: 0.0,
            body_length: 0.0,
            voxel_count,
            steps: 0,
            simulated_time: 0.0,
            settle_time: 0.0,
            dt: 0.0,
            centre_of_mass_trace: Vec::new(),
        }
    }

    /// The fitness if the evaluation completed.
    pub fn completed_fitness(&self) -> Option<f64> {
        (self.status == LocomotionStatus::Completed).then_some(self.fitness)
    }
}

/// Where a locomotion simulation is when it calls its observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocomotionPhase {
    /// After each settling check (every `settle.check_interval`).
    Settling,
    /// Settling has ended; actuation starts next.
    Settled,
    /// After sample `sample` (1-based) of `samples_per_cycle` in actuation cycle `cycle` (0-based).
    Actuating { cycle: u32, sample: u32 },
}

/// Evaluates a design for forward locomotion. Deterministic bit for bit; never panics on a
/// design (degenerate inputs become a status).
pub fn simulate_locomotion(
    grid: &VoxelGrid,
    palette: &Palette,
    scene: &DynamicScene,
) -> LocomotionOutcome {
    simulate_locomotion_observed(grid, palette, scene, 1, &mut |_, _| {})
}

/// [`simulate_locomotion`] that also hands the simulation to `observer` at every settling check
/// and `samples_per_cycle` times per actuation cycle (evenly in steps), for recordings such as a
/// dense centre-of-mass trace or animation frames. The observer runs between chunks of steps,
/// never inside the step loop, and the chunks add up to the same steps, so the outcome is bit
/// for bit that of [`simulate_locomotion`].
pub fn simulate_locomotion_observed(
    grid: &VoxelGrid,
    palette: &Palette,
    scene: &DynamicScene,
    samples_per_cycle: u32,
    observer: &mut dyn FnMut(LocomotionPhase, &Simulation),
) -> LocomotionOutcome {
    let body = keep_largest_component(grid);
    let voxel_count = body.filled_count();
    if voxel_count == 0 {
        return LocomotionOutcome::failed(LocomotionStatus::Empty, 0);
    }
    let mut sim = match Simulation::new(&body, palette, scene) {
        Ok(sim) => sim,
        Err(e) => {
            return LocomotionOutcome::failed(
                LocomotionStatus::Invalid {
                    message: e.to_string(),
                },
                voxel_count,
            );
        }
    };
    let (min_x, max_x) = sim
        .cells()
        .iter()
        .fold((u16::MAX, 0), |(lo, hi), c| (lo.min(c[0]), hi.max(c[0])));
    let body_length = f64::from(max_x - min_x + 1) * scene.voxel_size;
    let mut outcome = LocomotionOutcome {
        body_length,
        dt: sim.dt(),
        ..LocomotionOutcome::failed(LocomotionStatus::Completed, voxel_count)
    };
    let result = run(
        &mut sim,
        scene,
        samples_per_cycle.max(1),
        observer,
        &mut outcome,
    );
    outcome.steps = sim.steps();
    outcome.simulated_time = sim.time();
    if let Err(d) = result {
        outcome.status = LocomotionStatus::Diverged {
            reason: d.reason,
            time: d.time,
        };
        outcome.fitness = 0.0;
        outcome.displacement = 0.0;
        outcome.speed_percent_per_cycle = 0.0;
    }
    outcome
}

fn run(
    sim: &mut Simulation,
    scene: &DynamicScene,
    samples_per_cycle: u32,
    observer: &mut dyn FnMut(LocomotionPhase, &Simulation),
    outcome: &mut LocomotionOutcome,
) -> Result<(), super::simulation::Divergence> {
    let rule = &scene.settle;
    while sim.time() < rule.max_time {
        let chunk = rule.check_interval.min(rule.max_time - sim.time());
        sim.run_for(chunk)?;
        observer(LocomotionPhase::Settling, sim);
        if rule.still_speed > 0.0 && sim.max_speed() < rule.still_speed {
            break;
        }
    }
    observer(LocomotionPhase::Settled, sim);
    outcome.settle_time = sim.time();
    let start = sim.centre_of_mass();
    let to_array = |c: Vec3| [c.x, c.y, c.z];
    outcome.centre_of_mass_trace.push(to_array(start));
    if let Some(actuation) = &scene.actuation {
        sim.start_actuation();
        let steps_per_cycle = (actuation.period / sim.dt()).round().max(1.0) as u64;
        let samples = u64::from(samples_per_cycle);
        for cycle in 0..scene.actuation_cycles {
            // Sample k ends at step round(k · steps / samples) of the cycle.
            let mut done = 0;
            for sample in 1..=samples_per_cycle {
                let end = (u64::from(sample) * steps_per_cycle + samples / 2) / samples;
                sim.run_steps(end - done)?;
                done = end;
                observer(LocomotionPhase::Actuating { cycle, sample }, sim);
            }
            outcome
                .centre_of_mass_trace
                .push(to_array(sim.centre_of_mass()));
        }
    }
    let end = sim.centre_of_mass();
    outcome.displacement = end.x - start.x;
    outcome.fitness = match scene.fitness {
        LocomotionFitness::TotalDisplacement => outcome.displacement,
        LocomotionFitness::SteadyGait => {
            let xs: Vec<f64> = outcome.centre_of_mass_trace.iter().map(|c| c[0]).collect();
            let per_cycle: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
            let cycles = per_cycle.len() as f64;
            median(per_cycle) * cycles
        }
    };
    let cycles = f64::from(scene.actuation_cycles.max(1));
    outcome.speed_percent_per_cycle = 100.0 * outcome.fitness / outcome.body_length / cycles;
    Ok(())
}

/// The median (mean of the middle two for an even count), 0 for none. Values are finite here:
/// a non-finite state ends the simulation as a divergence first.
fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn median_ignores_a_one_off_jump() {
        assert_eq!(median(vec![]), 0.0);
        assert_eq!(median(vec![3.0]), 3.0);
        assert_eq!(median(vec![0.1, 9.0, 0.3]), 0.3);
        assert_eq!(median(vec![0.2, 0.1, 6.0, 0.3]), 0.25);
    }
}
