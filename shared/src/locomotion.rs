//! The locomotion task (paper §IV) as an evaluation: genome → voxels → the largest body settled on
//! the floor and actuated → fitness = centre-of-mass travel along +X. The simulation itself is
//! [`crate::dynamics::simulate_locomotion`]; this module adds the scene a config names, the
//! mapping to an [`Outcome`], and the resolution-independent physical size.

use serde::{Deserialize, Serialize};

use crate::dynamics::{DynamicScene, LocomotionStatus, foam_palette, simulate_locomotion};
use crate::genome::{Genome, GenomeLimits};
use crate::material::Palette;
use crate::outcome::{Failure, Metrics, Outcome};
use crate::voxel::{DEFAULT_THRESHOLD, GridDims, VoxelGrid, keep_largest_component, voxelize};

/// Everything a locomotion evaluation needs besides the genome and the resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocomotionScene {
    /// A passive and an actuated material (default: the paper's foams, μs 1.0, μk 0.3).
    pub palette: Palette,
    /// Longest side of the workspace, m (default 0.02: 1 mm voxels at 20×20×20). The voxel size is
    /// this over the grid's longest count, so a genome is the same physical robot at every
    /// resolution; `dynamics.voxel_size` is replaced by it.
    pub workspace: f64,
    /// Total-density threshold of the voxelization.
    pub threshold: f64,
    /// Ranges and size limit a genome must respect.
    pub limits: GenomeLimits,
    /// The physics: floor, gravity, actuation, damping, settling, cycles (default: the paper's).
    pub dynamics: DynamicScene,
}

impl Default for LocomotionScene {
    fn default() -> Self {
        Self {
            palette: foam_palette(),
            workspace: 0.02,
            threshold: DEFAULT_THRESHOLD,
            limits: GenomeLimits::default(),
            dynamics: DynamicScene::paper_locomotion(),
        }
    }
}

impl LocomotionScene {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        self.palette
            .validate()
            .map_err(|e| format!("palette: {e}"))?;
        self.limits.validate().map_err(|e| e.to_string())?;
        if !(self.workspace.is_finite() && self.workspace > 0.0) {
            return Err(format!("workspace = {} must be positive", self.workspace));
        }
        if !self.threshold.is_finite() {
            return Err(format!("threshold = {} must be finite", self.threshold));
        }
        self.dynamics
            .validate()
            .map_err(|e| format!("dynamics: {e}"))?;
        if self.dynamics.floor.is_none() {
            return Err("dynamics.floor: locomotion needs a floor to push against".into());
        }
        if self.dynamics.actuation.is_none() {
            return Err("dynamics.actuation: locomotion needs actuation".into());
        }
        if !self.palette.0.iter().any(|m| m.actuated) {
            return Err("palette: no material is actuated, so no design can move".into());
        }
        Ok(())
    }

    /// The dynamics scene at resolution `dims`: the voxel size follows the workspace.
    pub fn dynamics_at(&self, dims: GridDims) -> DynamicScene {
        let longest = dims.nx.max(dims.ny).max(dims.nz) as f64;
        DynamicScene {
            voxel_size: self.workspace / longest,
            ..self.dynamics.clone()
        }
    }
}

/// What a locomotion evaluation measured, for reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocomotionMetrics {
    /// Centre-of-mass travel along +X over the actuation cycles, m.
    pub displacement: f64,
    /// The fitness: the same travel as the scene's `dynamics.fitness` measures it, m (by default
    /// the median per-cycle travel times the cycles, which a one-off topple does not move).
    #[serde(default)]
    pub gait_displacement: f64,
    /// Travel per cycle in % of body length (the paper's Table IV measure).
    pub speed_percent_per_cycle: f64,
    /// Extent of the settled body along X, m.
    pub body_length: f64,
    /// Voxels of the largest body, and of each material.
    pub voxels: usize,
    pub material_counts: Vec<usize>,
    /// Simulation steps, time step and simulated time (settling included), s.
    pub steps: u64,
    pub dt: f64,
    pub simulated_time: f64,
    pub settle_time: f64,
    /// Centre of mass after settling and after each cycle, m.
    pub centre_of_mass_trace: Vec<[f64; 3]>,
}

/// The robot a genome makes at `dims`: its largest face-connected body.
pub fn locomotion_design(genome: &Genome, scene: &LocomotionScene, dims: GridDims) -> VoxelGrid {
    let grid = voxelize(genome, dims, scene.palette.len(), scene.threshold);
    keep_largest_component(&grid)
}

/// Evaluates a genome as a walking robot at resolution `dims`. Every way a design can fail
/// (empty, invalid, diverged) is an outcome, never a panic or a NaN.
pub fn evaluate_locomotion(genome: &Genome, scene: &LocomotionScene, dims: GridDims) -> Outcome {
    if let Err(e) = genome.validate(&scene.limits, scene.palette.len()) {
        return Outcome::failed(Failure::InvalidGenome(e.to_string()));
    }
    let body = locomotion_design(genome, scene, dims);
    let result = simulate_locomotion(&body, &scene.palette, &scene.dynamics_at(dims));
    match result.status {
        LocomotionStatus::Completed => {
            let metrics = LocomotionMetrics {
                displacement: result.displacement,
                gait_displacement: result.fitness,
                speed_percent_per_cycle: result.speed_percent_per_cycle,
                body_length: result.body_length,
                voxels: result.voxel_count,
                material_counts: body.material_counts(scene.palette.len()),
                steps: result.steps,
                dt: result.dt,
                simulated_time: result.simulated_time,
                settle_time: result.settle_time,
                centre_of_mass_trace: result.centre_of_mass_trace,
            };
            Outcome::evaluated(result.fitness, Metrics::Locomotion(metrics))
        }
        LocomotionStatus::Empty => Outcome::failed(Failure::Empty),
        LocomotionStatus::Invalid { message } => Outcome::failed(Failure::InvalidRequest(message)),
        LocomotionStatus::Diverged { reason, time } => Outcome::failed(Failure::Diverged {
            reason: reason.to_string(),
            time,
        }),
    }
}
