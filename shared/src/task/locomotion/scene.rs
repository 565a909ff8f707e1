//! The locomotion scene (paper §IV): a soft robot on a floor, actuated volumetrically, that must
//! travel along a heading, on level ground or up an incline.

use serde::{Deserialize, Serialize};

use super::protocol::{LocomotionFitness, LocomotionProtocol, SettleRule};
use super::starts::Starts;
use crate::dynamics::{DynamicScene, foam_palette};
use crate::genome::GenomeLimits;
use crate::material::Palette;
use crate::task::SceneError;
use crate::task::error::{finite, positive};
use crate::voxel::{DEFAULT_THRESHOLD, GridDims};

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
    /// The direction the robot must travel, degrees in the floor plane from +X towards +Y.
    /// Default 0 (+X, the paper's). The fitness is travel along it; the drift across it is
    /// reported as `lateral`.
    pub heading_degrees: f64,
    /// Slope of the floor, degrees, rising along the heading: 10 means walking up a 10° slope,
    /// −10 down it. Default 0 (level). Gravity is tilted; the floor stays at z = 0.
    pub incline_degrees: f64,
    /// How the body settles under gravity before actuation starts.
    pub settle: SettleRule,
    /// Number of actuation cycles after settling. Default 10 (the paper's).
    pub actuation_cycles: u32,
    /// How the centre of mass's travel becomes the fitness (default: the steady gait).
    pub fitness: LocomotionFitness,
    /// How many times the settled body is switched on, each a fraction of a period later; the
    /// median start is the fitness (default: one start, the paper's protocol).
    pub starts: Starts,
    /// The physics: floor, gravity, actuation, damping, time step (default: the paper's).
    /// `voxel_size` follows `workspace` and the floor's incline follows `incline_degrees`.
    /// A `[scene.dynamics]` table changes only the keys it names: the rest stay the paper's, the
    /// actuation included.
    #[serde(deserialize_with = "paper_dynamics_where_unset")]
    pub dynamics: DynamicScene,
}

/// A dynamics table that leaves out `actuation` keeps the paper's: otherwise a config that only
/// changes, say, the floor's friction law would read as a robot that cannot move (a generic
/// dynamic scene has no actuation by default, and TOML cannot write "none" for it anyway).
fn paper_dynamics_where_unset<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> Result<DynamicScene, D::Error> {
    let mut dynamics = DynamicScene::deserialize(deserializer)?;
    if dynamics.actuation.is_none() {
        dynamics.actuation = DynamicScene::paper_locomotion().actuation;
    }
    Ok(dynamics)
}

impl Default for LocomotionScene {
    fn default() -> Self {
        let protocol = LocomotionProtocol::default();
        Self {
            palette: foam_palette(),
            workspace: 0.02,
            threshold: DEFAULT_THRESHOLD,
            limits: GenomeLimits::default(),
            heading_degrees: 0.0,
            incline_degrees: 0.0,
            settle: protocol.settle,
            actuation_cycles: protocol.actuation_cycles,
            fitness: protocol.fitness,
            starts: protocol.starts,
            dynamics: DynamicScene::paper_locomotion(),
        }
    }
}

impl LocomotionScene {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), SceneError> {
        crate::task::Task::design_space(self).validate()?;
        positive("workspace", self.workspace)?;
        finite("heading_degrees", self.heading_degrees)?;
        if !(self.incline_degrees.is_finite() && self.incline_degrees.abs() < 90.0) {
            return Err(SceneError::new(
                "incline_degrees",
                format!("{} must be between -90 and 90", self.incline_degrees),
            ));
        }
        self.protocol().validate()?;
        let floor = self.dynamics.floor.as_ref().ok_or_else(|| {
            SceneError::new("dynamics.floor", "locomotion needs a floor to push against")
        })?;
        if floor.incline != 0.0 || floor.downhill != 0.0 {
            return Err(SceneError::new(
                "dynamics.floor.incline",
                "set the slope with incline_degrees (it follows the heading)",
            ));
        }
        self.dynamics
            .validate()
            .map_err(|e| SceneError::new("dynamics", e.to_string()))?;
        if self.dynamics.actuation.is_none() {
            return Err(SceneError::new(
                "dynamics.actuation",
                "locomotion needs actuation",
            ));
        }
        if !self.palette.0.iter().any(|m| m.actuated) {
            return Err(SceneError::new(
                "palette",
                "no material is actuated, so no design can move",
            ));
        }
        Ok(())
    }

    /// The settle → actuate → score protocol this scene runs.
    pub fn protocol(&self) -> LocomotionProtocol {
        LocomotionProtocol {
            settle: self.settle.clone(),
            actuation_cycles: self.actuation_cycles,
            fitness: self.fitness,
            heading: self.heading_degrees.to_radians(),
            starts: self.starts.clone(),
        }
    }

    /// The dynamics scene at resolution `dims`: the voxel size follows the workspace, and the
    /// floor rises along the heading by `incline_degrees` (downhill is the opposite way).
    pub fn dynamics_at(&self, dims: GridDims) -> DynamicScene {
        let longest = dims.nx.max(dims.ny).max(dims.nz) as f64;
        let mut scene = DynamicScene {
            voxel_size: self.workspace / longest,
            ..self.dynamics.clone()
        };
        if self.incline_degrees != 0.0
            && let Some(floor) = scene.floor.as_mut()
        {
            floor.incline = self.incline_degrees.to_radians();
            floor.downhill = self.heading_degrees.to_radians() + std::f64::consts::PI;
        }
        scene
    }
}

/// What a locomotion evaluation measured, for reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocomotionMetrics {
    /// Centre-of-mass travel along the heading over the actuation cycles, m.
    pub displacement: f64,
    /// The fitness: the same travel as the scene's `fitness` measures it, m (by default the
    /// median per-cycle travel times the cycles, which a one-off topple does not move).
    #[serde(default)]
    pub gait_displacement: f64,
    /// Centre-of-mass drift across the heading (positive to its left) over the cycles, m.
    #[serde(default)]
    pub lateral: f64,
    /// Travel per cycle in % of body length (the paper's Table IV measure).
    pub speed_percent_per_cycle: f64,
    /// Extent of the settled body along the heading, m.
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
    /// With several starts, each start's fitness in start order, m; the fields above describe
    /// the median start. Empty for one start.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub start_fitness: Vec<f64>,
}
