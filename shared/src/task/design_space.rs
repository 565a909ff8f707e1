//! What every task's designs are made of, whatever the task: the materials a genome's points
//! name, the ranges of a point's parameters, and the density a voxel needs to be filled. Each
//! scene keeps these as its own `palette`, `limits` and `threshold` keys; the [`super::Task`]
//! trait reads them through this one view and checks them in one place.

use super::SceneError;
use super::error::finite;
use crate::genome::GenomeLimits;
use crate::material::Palette;

/// A task's genome space, borrowed from its scene.
#[derive(Clone, Copy, Debug)]
pub struct DesignSpace<'a> {
    /// The materials genome indices refer to.
    pub palette: &'a Palette,
    /// Ranges and size limit a genome must respect.
    pub limits: &'a GenomeLimits,
    /// Total-density threshold of the voxelization.
    pub threshold: f64,
}

impl DesignSpace<'_> {
    /// Checks the palette, the limits and the threshold, naming the key at fault.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.palette
            .validate()
            .map_err(|e| SceneError::new("palette", e.to_string()))?;
        self.limits
            .validate()
            .map_err(|e| SceneError::new("limits", e.to_string()))?;
        finite("threshold", self.threshold)
    }
}
