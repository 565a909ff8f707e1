//! The beam designer's task (paper §III): cantilevers that deflect into a prescribed profile.

mod custom;
mod evaluate;
mod report;
mod scene;
mod target;

use std::path::Path;

pub use custom::{CustomProfile, Interpolation, MAX_PROFILE_POINTS, TargetError};
pub use evaluate::simulate_beam;
pub use scene::{BeamMetrics, BeamScene};
pub use target::{NamedProfile, TargetProfile};

use super::cantilever::check_cantilever_dims;
use super::objectives::{self, Objective, Sense};
use super::{
    Artefact, DesignSpace, Figure, ImplausibleClaim, LayerLoadCase, ResolutionError, SceneError,
    SimulatorSettings, Task, TaskOutcome,
};
use crate::dynamics::DynamicScene;
use crate::genome::Genome;
use crate::report::Block;
use crate::voxel::{GridDims, VoxelGrid, keep_connected_to_base};

impl Task for BeamScene {
    type Metrics = BeamMetrics;

    const FIGURE: Figure = Figure {
        column: "rms_percent",
        axis: "RMS ERROR (% OF TIP DEFLECTION)",
        log: true,
    };
    const HAS_TARGET: bool = true;
    /// The static solve held 11.2 kB per voxel from 12x48x12 to 32x96x32.
    const BYTES_PER_VOXEL: u64 = 16 << 10;

    fn validate(&self) -> Result<(), SceneError> {
        BeamScene::validate(self)
    }

    fn load_files(&mut self, base_dir: &Path) -> Result<(), SceneError> {
        match &mut self.target {
            TargetProfile::Custom(p) => p
                .load_csv(base_dir)
                .map_err(|e| SceneError::new("target", e.to_string())),
            TargetProfile::Named(_) => Ok(()),
        }
    }

    fn design_space(&self) -> DesignSpace<'_> {
        DesignSpace {
            palette: &self.palette,
            limits: &self.limits,
            threshold: self.threshold,
        }
    }

    /// The beam is a physical length along Y: the voxel size is that over the layer count.
    fn voxel_size(&self, dims: GridDims) -> f64 {
        self.length / dims.ny as f64
    }

    fn check_dims(&self, dims: GridDims) -> Result<(), ResolutionError> {
        check_cantilever_dims(dims)
    }

    /// Only voxels face-connected to the clamped `y = 0` layer carry load.
    fn keep(&self, grid: &VoxelGrid) -> VoxelGrid {
        keep_connected_to_base(grid)
    }

    fn simulate(&self, design: &VoxelGrid) -> TaskOutcome<BeamMetrics> {
        simulate_beam(design, self)
    }

    fn check_metrics(
        &self,
        fitness: f64,
        metrics: &BeamMetrics,
        dims: GridDims,
    ) -> Result<(), ImplausibleClaim> {
        report::check_metrics(self, fitness, metrics, dims)
    }

    /// The error to four significant figures, so that a value just under the paper's reads as
    /// under it, with the paper's value beside it where the paper has one.
    fn headline(&self, m: &BeamMetrics) -> String {
        let rms = m.rms_percent;
        let decimals = if rms > 0.0 && rms.is_finite() {
            (3 - rms.log10().floor() as i32).clamp(0, 8) as usize
        } else {
            3
        };
        match self.target.paper_rms_percent() {
            Some(paper) => format!("RMS {rms:.decimals$} % (paper {paper:.2} %)"),
            None => format!("RMS {rms:.decimals$} %"),
        }
    }

    fn figure(&self, m: &BeamMetrics) -> f64 {
        m.rms_percent
    }

    fn meets_target(&self, m: &BeamMetrics, target: f64) -> bool {
        m.rms_percent <= target
    }

    const OBJECTIVES: &'static [Objective] = &[
        Objective {
            name: "rms",
            sense: Sense::Minimize,
            unit: "%",
            about: "the top surface's RMS deviation from the target, in % of the tip deflection",
        },
        Objective {
            name: "hard_fraction",
            sense: Sense::Minimize,
            unit: "",
            about: "the share of the workspace filled with the stiffest material",
        },
        Objective {
            name: "voxels",
            sense: Sense::Minimize,
            unit: "",
            about: "the design's voxels",
        },
        Objective {
            name: "mass",
            sense: Sense::Minimize,
            unit: "kg",
            about: "the design's mass, from its materials' densities",
        },
    ];

    fn objective_values(&self, m: &BeamMetrics, dims: GridDims) -> Vec<f64> {
        let counts = &m.material_counts;
        vec![
            m.rms_percent,
            objectives::fraction_of_cells(
                counts,
                objectives::stiffest(&self.palette),
                dims.cell_count(),
            ),
            m.voxels as f64,
            objectives::mass(counts, &self.palette, self.voxel_size(dims)),
        ]
    }

    fn summary(&self, metrics: Option<&BeamMetrics>) -> serde_json::Value {
        report::summary(self, metrics)
    }

    fn table(&self, metrics: Option<&BeamMetrics>, dims: GridDims) -> (String, Block) {
        report::table(self, metrics, dims)
    }

    fn write_artefacts(
        &self,
        dir: &Path,
        _genome: &Genome,
        _dims: GridDims,
        metrics: &BeamMetrics,
    ) -> std::io::Result<Vec<Artefact>> {
        report::write_profile(dir, metrics)
    }

    /// The cantilever in free space, no gravity, the link damping of the dynamics' default, with
    /// the tip load; a reader relaxes it to rest (VXA exports, docs/how-to/export.md).
    fn simulator_settings(
        &self,
        dims: GridDims,
        _metrics: Option<&BeamMetrics>,
    ) -> Option<SimulatorSettings> {
        let voxel_size = self.length / dims.ny as f64;
        let stiffest = self
            .palette
            .0
            .iter()
            .map(|m| m.youngs_modulus)
            .fold(0.0, f64::max);
        let (width, height) = (dims.nx as f64 * voxel_size, dims.nz as f64 * voxel_size);
        let inertia = width * height.powi(3) / 12.0;
        let deflection = self.tip_load * self.length.powi(3) / (3.0 * stiffest * inertia);
        Some(SimulatorSettings {
            scene: DynamicScene {
                voxel_size,
                gravity: 0.0,
                floor: None,
                ..DynamicScene::default()
            },
            settle_time: 0.0,
            cycles: 0,
            load_case: Some(LayerLoadCase {
                tip_force: [0.0, 0.0, -self.tip_load],
                min_strain_energy: 0.5 * self.tip_load * deflection,
            }),
        })
    }
}
