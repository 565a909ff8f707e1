//! The beam scene (paper §III): a cantilever clamped at its −Y layer and loaded downward at its
//! free-end layer, and what an evaluation of it measures.

use serde::{Deserialize, Serialize};

use super::target::TargetProfile;
use crate::genome::GenomeLimits;
use crate::material::Palette;
use crate::statics::StaticSolverParams;
use crate::task::SceneError;
use crate::task::cantilever::check_load_case;
use crate::voxel::DEFAULT_THRESHOLD;

/// Everything a beam evaluation needs besides the genome and the resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamScene {
    /// The profile the deflected top surface should follow.
    pub target: TargetProfile,
    /// The materials genome indices refer to (default: hard and soft resin, 1000:1).
    #[serde(default = "Palette::hard_soft_resins")]
    pub palette: Palette,
    /// Edge length of the whole beam along Y in metres; the voxel size is this over the resolution's
    /// `ny`, so the same physical beam is simulated at every resolution.
    #[serde(default = "default_length")]
    pub length: f64,
    /// Total downward force on the free-end layer, N. The fitness is normalized by the tip
    /// deflection, so this only matters for the reported deflection in metres.
    #[serde(default = "default_tip_load")]
    pub tip_load: f64,
    /// Total-density threshold of the voxelization.
    #[serde(default = "default_threshold")]
    pub threshold: f64,
    /// Ranges and size limit a genome must respect.
    #[serde(default)]
    pub limits: GenomeLimits,
    /// Static solver settings.
    #[serde(default)]
    pub solver: StaticSolverParams,
}

fn default_length() -> f64 {
    0.04
}
fn default_tip_load() -> f64 {
    0.01
}
fn default_threshold() -> f64 {
    DEFAULT_THRESHOLD
}

impl BeamScene {
    pub fn new(target: impl Into<TargetProfile>) -> Self {
        Self {
            target: target.into(),
            palette: Palette::hard_soft_resins(),
            length: default_length(),
            tip_load: default_tip_load(),
            threshold: default_threshold(),
            limits: GenomeLimits::default(),
            solver: StaticSolverParams::default(),
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), SceneError> {
        crate::task::Task::design_space(self).validate()?;
        self.target.validate()?;
        check_load_case(self.length, self.tip_load, &self.solver, self.threshold)
    }
}

/// What a beam evaluation measured, for reports and plots.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BeamMetrics {
    /// RMS deviation of the normalized top surface from the target, percent of tip deflection
    /// (the paper's Table III measure).
    pub rms_percent: f64,
    /// Mean downward deflection of the tip layer's top surface, metres.
    pub tip_deflection: f64,
    /// Filled voxels connected to the clamp.
    pub voxels: usize,
    /// Of those, how many of each material.
    pub material_counts: Vec<usize>,
    /// Top-surface voxels (the highest of each column), averaged per station into the profile.
    pub surface_voxels: usize,
    /// Per station along the beam: normalized position, mean normalized deflection, target.
    pub profile: Vec<[f64; 3]>,
    /// Iterations the static solver took (0 for a direct solve).
    pub solver_iterations: usize,
    /// True relative residual of the solve.
    pub solver_residual: f64,
}
