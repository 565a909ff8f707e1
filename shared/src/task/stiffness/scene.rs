//! The stiffness scene: the stiffest cantilever for a budget of hard material — the compliance
//! problem homogenization-based topology optimization solves (the methods the paper sets itself
//! against, its ref. [1]), posed on the same clamp and tip load as the beam designer.

use serde::{Deserialize, Serialize};

use crate::genome::GenomeLimits;
use crate::material::Palette;
use crate::statics::StaticSolverParams;
use crate::task::SceneError;
use crate::task::cantilever::check_load_case;
use crate::voxel::DEFAULT_THRESHOLD;

/// Everything a stiffness evaluation needs besides the genome and the resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StiffnessScene {
    /// The materials genome indices refer to (default: hard and soft resin, 1000:1).
    pub palette: Palette,
    /// Which palette material is the budgeted hard one (default 0, the hard resin).
    pub hard_material: u8,
    /// At most this fraction of the workspace's voxels may be hard, in (0, 1]. Default 0.3.
    pub max_hard_fraction: f64,
    /// Edge length of the whole beam along Y, m; the voxel size is this over `ny`.
    pub length: f64,
    /// Total downward force on the free-end layer, N.
    pub tip_load: f64,
    /// Total-density threshold of the voxelization.
    pub threshold: f64,
    /// Ranges and size limit a genome must respect.
    pub limits: GenomeLimits,
    /// Static solver settings.
    pub solver: StaticSolverParams,
}

impl Default for StiffnessScene {
    fn default() -> Self {
        Self {
            palette: Palette::hard_soft_resins(),
            hard_material: 0,
            max_hard_fraction: 0.3,
            length: 0.04,
            tip_load: 0.01,
            threshold: DEFAULT_THRESHOLD,
            limits: GenomeLimits::default(),
            solver: StaticSolverParams::default(),
        }
    }
}

impl StiffnessScene {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), SceneError> {
        crate::task::Task::design_space(self).validate()?;
        if usize::from(self.hard_material) >= self.palette.len() {
            return Err(SceneError::new(
                "hard_material",
                format!(
                    "{} is not a material of the {}-material palette",
                    self.hard_material,
                    self.palette.len()
                ),
            ));
        }
        if !(self.max_hard_fraction > 0.0 && self.max_hard_fraction <= 1.0) {
            return Err(SceneError::new(
                "max_hard_fraction",
                format!("{} must be in (0, 1]", self.max_hard_fraction),
            ));
        }
        check_load_case(self.length, self.tip_load, &self.solver, self.threshold)
    }
}

/// What a stiffness evaluation measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StiffnessMetrics {
    /// Mean downward deflection of the tip layer, m (every tip voxel, not only the top surface).
    pub tip_deflection: f64,
    /// Tip stiffness relative to the whole workspace filled with hard material, by beam theory
    /// (P l³ / 3EI over the clamp-to-tip lever l): the fitness of a design within its budget.
    pub relative_stiffness: f64,
    /// Hard voxels over the workspace's voxels.
    pub hard_fraction: f64,
    /// Whether `hard_fraction` is within the scene's budget.
    pub within_budget: bool,
    /// Filled voxels connected to the clamp, and of each material.
    pub voxels: usize,
    pub material_counts: Vec<usize>,
    /// How much of the hard material's bending stiffness the sections reach, against the flanged
    /// (I-beam) layout beam theory calls optimal for the same hard area per layer: the second
    /// moment of area of the hard voxels about their centroid, over that of the same count packed
    /// into the top and bottom rows, averaged over the layers of the root half (where the moment
    /// is largest) weighted by their hard area. 1 is a perfect flange layout.
    pub flange_efficiency: f64,
    /// Iterations the static solver took and its true relative residual.
    pub solver_iterations: usize,
    pub solver_residual: f64,
}
