//! Scenes: everything a task needs besides the genome and the resolution, validated once.

use serde::{Deserialize, Serialize};

use crate::beam::BeamScene;
use crate::genome::{Genome, GenomeLimits};
use crate::locomotion::LocomotionScene;
use crate::material::Palette;
use crate::voxel::{GridDims, VoxelGrid};

/// The kinds of task Amorph can evaluate, tagged by `kind` in configs and on the wire.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Scene {
    /// A cantilever that must deflect into a target profile (paper §III).
    Beam(BeamScene),
    /// A soft robot that must walk along +X on the floor by volumetric actuation (paper §IV).
    Locomotion(LocomotionScene),
}

impl Scene {
    pub fn palette(&self) -> &Palette {
        match self {
            Scene::Beam(b) => &b.palette,
            Scene::Locomotion(l) => &l.palette,
        }
    }

    pub fn limits(&self) -> &GenomeLimits {
        match self {
            Scene::Beam(b) => &b.limits,
            Scene::Locomotion(l) => &l.limits,
        }
    }

    /// The voxels a genome makes at `dims`, after the task keeps what it can use (the part
    /// connected to the clamp for a beam, the largest body for a robot).
    pub fn design(&self, genome: &Genome, dims: GridDims) -> VoxelGrid {
        match self {
            Scene::Beam(b) => crate::beam::beam_design(genome, b, dims),
            Scene::Locomotion(l) => crate::locomotion::locomotion_design(genome, l, dims),
        }
    }

    /// Edge length of one voxel at resolution `dims`, m.
    pub fn voxel_size(&self, dims: GridDims) -> f64 {
        match self {
            Scene::Beam(b) => b.length / dims.ny as f64,
            Scene::Locomotion(l) => l.dynamics_at(dims).voxel_size,
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Scene::Beam(b) => b.validate(),
            Scene::Locomotion(l) => l.validate(),
        }
    }
}
