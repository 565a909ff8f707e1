//! Scenes: everything a task needs besides the genome and the resolution, validated once.

use serde::{Deserialize, Serialize};

use crate::beam::BeamScene;
use crate::genome::GenomeLimits;
use crate::material::Palette;

/// The kinds of task Amorph can evaluate, tagged by `kind` in configs and on the wire.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Scene {
    /// A cantilever that must deflect into a target profile (paper §III).
    Beam(BeamScene),
}

impl Scene {
    pub fn palette(&self) -> &Palette {
        match self {
            Scene::Beam(b) => &b.palette,
        }
    }

    pub fn limits(&self) -> &GenomeLimits {
        match self {
            Scene::Beam(b) => &b.limits,
        }
    }

    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Scene::Beam(b) => b.validate(),
        }
    }
}
