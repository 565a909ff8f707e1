//! The walking-robot task (paper §IV): genome → voxels → the largest body settled on the floor and
//! actuated → fitness = the centre of mass's steady travel along the heading.

mod animation;
mod protocol;
mod recording;
mod report;
mod scene;
mod starts;
mod trajectory;

use std::path::Path;

pub use animation::{AnimationError, AnimationOptions, animation_gif, write_locomotion_animation};
pub use protocol::{
    LocomotionFitness, LocomotionOutcome, LocomotionPhase, LocomotionProtocol, LocomotionStatus,
    SettleRule, simulate_locomotion, simulate_locomotion_observed,
};
pub use recording::{LocomotionRecording, RecordingOptions, Sample, record_locomotion};
pub use report::PAPER_SPEED_PERCENT_PER_CYCLE;
pub use scene::{LocomotionMetrics, LocomotionScene};
pub use starts::Starts;
pub use trajectory::{trajectory_csv, trajectory_plot};

use super::objectives::{self, Objective, Sense};
use super::{
    Artefact, DesignSpace, Figure, ImplausibleClaim, ResolutionError, SceneError,
    SimulatorSettings, Task, TaskOutcome,
};
use crate::genome::Genome;
use crate::outcome::Failure;
use crate::report::Block;
use crate::voxel::{GridDims, VoxelGrid, keep_largest_component};

impl Task for LocomotionScene {
    type Metrics = LocomotionMetrics;

    const FIGURE: Figure = Figure {
        column: "gait_mm",
        axis: "DISPLACEMENT (MM)",
        log: false,
    };
    const HAS_TARGET: bool = false;
    /// The simulation held 0.53 kB per voxel.
    const BYTES_PER_VOXEL: u64 = 2 << 10;

    fn validate(&self) -> Result<(), SceneError> {
        LocomotionScene::validate(self)
    }

    fn design_space(&self) -> DesignSpace<'_> {
        DesignSpace {
            palette: &self.palette,
            limits: &self.limits,
            threshold: self.threshold,
        }
    }

    /// The robot's size is the workspace: the voxel size is that over the longest count.
    fn voxel_size(&self, dims: GridDims) -> f64 {
        self.dynamics_at(dims).voxel_size
    }

    fn check_dims(&self, _dims: GridDims) -> Result<(), ResolutionError> {
        Ok(())
    }

    /// A robot is one body: its largest face-connected part.
    fn keep(&self, grid: &VoxelGrid) -> VoxelGrid {
        keep_largest_component(grid)
    }

    fn simulate(&self, body: &VoxelGrid) -> TaskOutcome<LocomotionMetrics> {
        let dynamics = self.dynamics_at(body.dims());
        let result = simulate_locomotion(body, &self.palette, &dynamics, &self.protocol());
        match result.status {
            LocomotionStatus::Completed => {
                let metrics = LocomotionMetrics {
                    displacement: result.displacement,
                    gait_displacement: result.fitness,
                    lateral: result.lateral,
                    speed_percent_per_cycle: result.speed_percent_per_cycle,
                    body_length: result.body_length,
                    voxels: result.voxel_count,
                    material_counts: body.material_counts(self.palette.len()),
                    steps: result.steps,
                    dt: result.dt,
                    simulated_time: result.simulated_time,
                    settle_time: result.settle_time,
                    centre_of_mass_trace: result.centre_of_mass_trace,
                    start_fitness: result.start_fitness,
                };
                TaskOutcome::evaluated(result.fitness, metrics)
            }
            LocomotionStatus::Empty => TaskOutcome::failed(Failure::Empty),
            LocomotionStatus::Invalid { message } => {
                TaskOutcome::failed(Failure::InvalidRequest(message))
            }
            LocomotionStatus::Diverged { reason, time } => {
                TaskOutcome::failed(Failure::Diverged { reason, time })
            }
        }
    }

    fn check_metrics(
        &self,
        fitness: f64,
        metrics: &LocomotionMetrics,
        dims: GridDims,
    ) -> Result<(), ImplausibleClaim> {
        report::check_metrics(self, fitness, metrics, dims)
    }

    fn headline(&self, m: &LocomotionMetrics) -> String {
        format!(
            "gait {:.2} mm ({:.2} % body length/cycle), travel {:.2} mm",
            1e3 * m.gait_displacement,
            m.speed_percent_per_cycle,
            1e3 * m.displacement
        )
    }

    fn figure(&self, m: &LocomotionMetrics) -> f64 {
        1e3 * m.gait_displacement
    }

    fn meets_target(&self, _m: &LocomotionMetrics, _target: f64) -> bool {
        false
    }

    const OBJECTIVES: &'static [Objective] = &[
        Objective {
            name: "speed",
            sense: Sense::Maximize,
            unit: "mm",
            about: "the gait's travel over the actuation cycles (the fitness)",
        },
        Objective {
            name: "voxels",
            sense: Sense::Minimize,
            unit: "",
            about: "the body's voxels",
        },
        Objective {
            name: "actuated_fraction",
            sense: Sense::Minimize,
            unit: "",
            about: "the share of the body's voxels made of an actuated material",
        },
    ];

    fn objective_values(&self, m: &LocomotionMetrics, _dims: GridDims) -> Vec<f64> {
        vec![
            self.figure(m),
            m.voxels as f64,
            objectives::actuated_fraction(&m.material_counts, &self.palette),
        ]
    }

    fn summary(&self, metrics: Option<&LocomotionMetrics>) -> serde_json::Value {
        report::summary(self, metrics)
    }

    fn table(&self, metrics: Option<&LocomotionMetrics>, dims: GridDims) -> (String, Block) {
        report::table(self, metrics, dims)
    }

    /// The best robot walking (animation.gif), its centre of mass's path (trajectory.png, .csv),
    /// from one more simulation of it.
    fn write_artefacts(
        &self,
        dir: &Path,
        genome: &Genome,
        dims: GridDims,
        _metrics: &LocomotionMetrics,
    ) -> std::io::Result<Vec<Artefact>> {
        report::write_pictures(self, dir, genome, dims)
    }

    fn simulator_settings(
        &self,
        dims: GridDims,
        metrics: Option<&LocomotionMetrics>,
    ) -> Option<SimulatorSettings> {
        let mut scene = self.dynamics_at(dims);
        // The files run the start whose gait is the fitness.
        if let (Some(m), Some(actuation)) = (metrics, scene.actuation.as_mut())
            && !m.start_fitness.is_empty()
        {
            actuation.phase += self.starts.phase(Starts::median_start(&m.start_fitness));
        }
        Some(SimulatorSettings {
            scene,
            settle_time: metrics.map_or(self.settle.max_time, |m| m.settle_time),
            cycles: self.actuation_cycles,
            load_case: None,
        })
    }
}
