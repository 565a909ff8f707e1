//! The stiffness task: the stiffest cantilever for a budget of hard material (minimum compliance
//! under the beam designer's clamp and tip load, with at most `max_hard_fraction` of the
//! workspace hard, the rest soft or empty). This folder and one registration line in
//! `task/mod.rs` are all of it: the proof that a task is one boundary.

mod evaluate;
mod report;
mod scene;

use std::path::Path;

pub use evaluate::simulate_stiffness;
pub use scene::{StiffnessMetrics, StiffnessScene};

use super::cantilever::check_cantilever_dims;
use super::objectives::{Objective, Sense};
use super::{
    Artefact, DesignSpace, Figure, ImplausibleClaim, ResolutionError, SceneError,
    SimulatorSettings, Task, TaskOutcome,
};
use crate::genome::Genome;
use crate::report::Block;
use crate::voxel::{GridDims, VoxelGrid, keep_connected_to_base};

impl Task for StiffnessScene {
    type Metrics = StiffnessMetrics;

    const FIGURE: Figure = Figure {
        column: "relative_stiffness",
        axis: "TIP STIFFNESS / ALL-HARD BEAM'S",
        log: false,
    };
    const HAS_TARGET: bool = false;
    /// The beam's static solve, on the same load case.
    const BYTES_PER_VOXEL: u64 = 16 << 10;

    fn validate(&self) -> Result<(), SceneError> {
        StiffnessScene::validate(self)
    }

    fn design_space(&self) -> DesignSpace<'_> {
        DesignSpace {
            palette: &self.palette,
            limits: &self.limits,
            threshold: self.threshold,
        }
    }

    fn voxel_size(&self, dims: GridDims) -> f64 {
        self.length / dims.ny as f64
    }

    /// The same cantilever as the beam designer's.
    fn check_dims(&self, dims: GridDims) -> Result<(), ResolutionError> {
        check_cantilever_dims(dims)
    }

    fn keep(&self, grid: &VoxelGrid) -> VoxelGrid {
        keep_connected_to_base(grid)
    }

    fn simulate(&self, design: &VoxelGrid) -> TaskOutcome<StiffnessMetrics> {
        simulate_stiffness(design, self)
    }

    fn check_metrics(
        &self,
        fitness: f64,
        metrics: &StiffnessMetrics,
        dims: GridDims,
    ) -> Result<(), ImplausibleClaim> {
        report::check_metrics(self, fitness, metrics, dims)
    }

    fn headline(&self, m: &StiffnessMetrics) -> String {
        format!(
            "stiffness {:.4} of all-hard, {:.1} % hard{}",
            m.relative_stiffness,
            100.0 * m.hard_fraction,
            if m.within_budget {
                ""
            } else {
                " (over budget)"
            }
        )
    }

    fn figure(&self, m: &StiffnessMetrics) -> f64 {
        m.relative_stiffness
    }

    fn meets_target(&self, _m: &StiffnessMetrics, _target: f64) -> bool {
        false
    }

    const OBJECTIVES: &'static [Objective] = &[
        Objective {
            name: "compliance",
            sense: Sense::Minimize,
            unit: "J",
            about: "the tip load times the tip's deflection (the inverse of stiffness)",
        },
        Objective {
            name: "hard_fraction",
            sense: Sense::Minimize,
            unit: "",
            about: "the share of the workspace filled with the hard material",
        },
    ];

    fn objective_values(&self, m: &StiffnessMetrics, _dims: GridDims) -> Vec<f64> {
        vec![self.tip_load * m.tip_deflection, m.hard_fraction]
    }

    fn summary(&self, metrics: Option<&StiffnessMetrics>) -> serde_json::Value {
        report::summary(self, metrics)
    }

    fn table(&self, metrics: Option<&StiffnessMetrics>, dims: GridDims) -> (String, Block) {
        report::table(self, metrics, dims)
    }

    fn write_artefacts(
        &self,
        _dir: &Path,
        _genome: &Genome,
        _dims: GridDims,
        _metrics: &StiffnessMetrics,
    ) -> std::io::Result<Vec<Artefact>> {
        Ok(Vec::new())
    }

    fn simulator_settings(
        &self,
        _dims: GridDims,
        _metrics: Option<&Self::Metrics>,
    ) -> Option<SimulatorSettings> {
        None
    }
}
