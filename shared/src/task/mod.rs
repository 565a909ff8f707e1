//! Tasks: what a design is for. A task owns its scene (validated, naming the bad field), what it
//! keeps of a voxelized genome, its evaluation protocol and fitness, its metrics and headline, its
//! rows for summaries and reports (with the paper's figures where it has them), its pictures and
//! its stop rule. The simulators (`statics`, `dynamics`) know nothing of fitness; the coordinator,
//! worker, wire format and run store know nothing of any particular task: they meet tasks only
//! through [`Scene`] and [`Metrics`], which the [`tasks!`] registration below generates.
//!
//! Adding a task: a folder here with a scene type implementing [`Task`], and one line in the
//! registration (see ARCHITECTURE.md, "How to add a task").

pub mod beam;
pub mod cantilever;
mod design_space;
mod error;
mod kindless;
pub mod locomotion;
pub mod memory;
pub mod objectives;
pub mod scene_toml;
pub mod stiffness;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

pub use design_space::DesignSpace;
pub use error::{ImplausibleClaim, ResolutionError, SceneError};
pub use objectives::{Objective, Sense};

use crate::dynamics::DynamicScene;
use crate::genome::{Genome, GenomeLimits};
use crate::material::Palette;
use crate::outcome::Failure;
use crate::report::Block;
use crate::voxel::{GridDims, VoxelGrid, voxelize};

/// The figure a task's progress is followed by (history, progress plots): its name as a CSV
/// column, its axis label, and whether it is best read on a log axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Figure {
    pub column: &'static str,
    pub axis: &'static str,
    pub log: bool,
}

/// One picture or file a task wrote for the report, relative to the results folder.
#[derive(Clone, Debug, PartialEq)]
pub struct Artefact {
    pub path: String,
    /// `Some` for a picture shown in the report, `None` for a data file that is only linked.
    pub caption: Option<String>,
}

/// A task's simulation as another simulator should run it: the physics, and how long. A static
/// task (a beam) is run there by dynamic relaxation of its load case.
#[derive(Clone, Debug, PartialEq)]
pub struct SimulatorSettings {
    pub scene: DynamicScene,
    /// How long the body settles under gravity before actuation starts, s: the design's measured
    /// settle when the settings are a design's, else the longest the task allows.
    pub settle_time: f64,
    /// Actuation cycles measured after settling.
    pub cycles: u32,
    /// The static load case to relax to, for a static task; `None` for a robot.
    pub load_case: Option<LayerLoadCase>,
}

/// The cantilever load case as a simulator without a static solver should run it: the root layer
/// (y = 0) clamped in all six degrees of freedom, `tip_force` shared equally by the voxels of the
/// free-end layer (y = ny − 1), relaxed until the kinetic energy left is a negligible part of
/// `min_strain_energy`.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerLoadCase {
    /// Total force on the free-end layer, N.
    pub tip_force: [f64; 3],
    /// The strain energy the load stores in the stiffest design the scene allows (the full box
    /// of its stiffest material, as a slender beam: ½F·FL³/(3EI)), J. Every design stores at least
    /// this, so a kinetic energy set against it means rest for every design.
    pub min_strain_energy: f64,
}

/// A task: its scene is `Self`, its measurements `Self::Metrics`.
pub trait Task {
    type Metrics: Clone + std::fmt::Debug + PartialEq + Serialize + DeserializeOwned;

    /// The figure history and progress plots follow.
    const FIGURE: Figure;
    /// Whether the task has a stop target (`budget.target_rms_percent`), see [`Task::meets_target`].
    const HAS_TARGET: bool;
    /// Peak memory of an evaluation per voxel of the resolution, bytes, measured and rounded up
    /// (docs/how-to/cluster.md), so a worker refuses a task it could not finish.
    const BYTES_PER_VOXEL: u64;

    /// Checks every field, naming the first bad one.
    fn validate(&self) -> Result<(), SceneError>;
    /// Reads the files the scene names (a custom profile's CSV), relative to `base_dir`, the
    /// config's folder; the scene keeps their contents, so workers never read files.
    fn load_files(&mut self, _base_dir: &Path) -> Result<(), SceneError> {
        Ok(())
    }
    /// The genome space: palette, limits and threshold, as the scene's keys give them.
    fn design_space(&self) -> DesignSpace<'_>;
    /// The materials genome indices refer to.
    fn palette(&self) -> &Palette {
        self.design_space().palette
    }
    /// Ranges and size limit a genome must respect.
    fn limits(&self) -> &GenomeLimits {
        self.design_space().limits
    }
    /// Total-density threshold of the voxelization.
    fn threshold(&self) -> f64 {
        self.design_space().threshold
    }
    /// Edge length of one voxel at resolution `dims`, m.
    fn voxel_size(&self, dims: GridDims) -> f64;
    /// Whether the task can be evaluated at `dims` (a reason if not).
    fn check_dims(&self, dims: GridDims) -> Result<(), ResolutionError>;
    /// What the task keeps of a voxelized genome (the part it can use).
    fn keep(&self, grid: &VoxelGrid) -> VoxelGrid;
    /// Physics and fitness of a kept design. Every way a design can fail is an outcome.
    fn simulate(&self, design: &VoxelGrid) -> TaskOutcome<Self::Metrics>;
    /// Whether `fitness` and `metrics` claimed for a design at `dims` are ones this scene can
    /// produce: every number finite and inside what the physics allows, every count within the
    /// grid, the fitness the one the metrics give. Outcomes arrive from peers; this is how the
    /// coordinator refuses an impossible one before anything (a plot, a report) consumes it.
    fn check_metrics(
        &self,
        fitness: f64,
        metrics: &Self::Metrics,
        dims: GridDims,
    ) -> Result<(), ImplausibleClaim>;
    /// One line for progress and logs.
    fn headline(&self, metrics: &Self::Metrics) -> String;
    /// The value of [`Task::FIGURE`] for a design.
    fn figure(&self, metrics: &Self::Metrics) -> f64;
    /// The stop rule: whether `metrics` meet a `budget.target_rms_percent` target (never called
    /// unless [`Task::HAS_TARGET`]; the config refuses the key otherwise).
    fn meets_target(&self, metrics: &Self::Metrics, target: f64) -> bool;
    /// What a multi-objective search may trade off on this task.
    const OBJECTIVES: &'static [Objective];
    /// The values of [`Task::OBJECTIVES`], in their order, for a design evaluated at `dims`.
    fn objective_values(&self, metrics: &Self::Metrics, dims: GridDims) -> Vec<f64>;
    /// The task's fields of `summary.json`.
    fn summary(&self, metrics: Option<&Self::Metrics>) -> serde_json::Value;
    /// The report's section on the best design: a heading and a table, with the paper's
    /// reference figures beside ours where the paper has them.
    fn table(&self, metrics: Option<&Self::Metrics>, dims: GridDims) -> (String, Block);
    /// Task-specific pictures and data files of the best design, written into `dir`.
    fn write_artefacts(
        &self,
        dir: &Path,
        genome: &Genome,
        dims: GridDims,
        metrics: &Self::Metrics,
    ) -> std::io::Result<Vec<Artefact>>;
    /// How another simulator runs a design at `dims` as this task means it (written into VXA
    /// exports); with the design's `metrics`, settings that depend on the design (a robot's
    /// measured settle) are the design's own, without them the task's bounds.
    fn simulator_settings(
        &self,
        dims: GridDims,
        metrics: Option<&Self::Metrics>,
    ) -> Option<SimulatorSettings>;
}

/// An outcome with a task's own metrics.
pub type TaskOutcome<M> = crate::outcome::Outcome<M>;

/// The outcome every part of the system passes around: the registry's [`Metrics`].
pub type Outcome = crate::outcome::Outcome<Metrics>;

/// The voxels `genome` makes at `dims`, after `task` keeps what it can use.
pub fn design<T: Task>(task: &T, genome: &Genome, dims: GridDims) -> VoxelGrid {
    task.keep(&voxelize(
        genome,
        dims,
        task.palette().len(),
        task.threshold(),
    ))
}

/// The whole evaluation of a task: validate the genome, check the resolution, voxelize, keep,
/// simulate. Pure and deterministic.
fn evaluate_task<T: Task>(task: &T, genome: &Genome, dims: GridDims) -> TaskOutcome<T::Metrics> {
    if let Err(e) = genome.validate(task.limits(), task.palette().len()) {
        return TaskOutcome::failed(Failure::InvalidGenome(e.to_string()));
    }
    if let Err(reason) = task.check_dims(dims) {
        return TaskOutcome::failed(Failure::InvalidRequest(reason.to_string()));
    }
    task.simulate(&design(task, genome, dims))
}

/// Registers the tasks: generates [`Scene`] (tagged by `kind` in configs and on the wire) and
/// [`Metrics`] with one variant per task, and dispatches every [`Task`] method once, here.
macro_rules! tasks {
    ($($variant:ident = $kind:literal => $scene:ty),+ $(,)?) => {
        /// A task's scene: everything an evaluation needs besides the genome and the resolution.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(tag = "kind")]
        pub enum Scene {
            $(#[serde(rename = $kind)] $variant($scene)),+
        }

        /// A task's measurements behind a fitness.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub enum Metrics {
            $(#[serde(rename = $kind)] $variant(<$scene as Task>::Metrics)),+
        }

        impl Scene {
            /// Reads the scene `kind` names from its table, whose `kind` key is skipped: for error
            /// messages that name the bad key's line, which reading [`Scene`] itself cannot give
            /// (see [`kindless`]). A config is still read as [`Scene`].
            pub fn deserialize_kind<'de, D: serde::Deserializer<'de>>(
                kind: &str,
                table: D,
            ) -> Result<Self, D::Error> {
                match kind {
                    $($kind => <$scene as Deserialize>::deserialize(kindless::Kindless(table)).map(Scene::$variant),)+
                    other => Err(<D::Error as serde::de::Error>::unknown_variant(other, &[$($kind),+])),
                }
            }

            /// The `kind` of this scene in configs.
            pub fn kind(&self) -> &'static str {
                match self {
                    $(Scene::$variant(_) => $kind),+
                }
            }

            pub fn validate(&self) -> Result<(), SceneError> {
                match self { $(Scene::$variant(s) => s.validate()),+ }
            }

            /// Reads the files the scene names relative to `base_dir` (see [`Task::load_files`]).
            pub fn load_files(&mut self, base_dir: &Path) -> Result<(), SceneError> {
                match self { $(Scene::$variant(s) => s.load_files(base_dir)),+ }
            }

            pub fn palette(&self) -> &Palette {
                match self { $(Scene::$variant(s) => s.palette()),+ }
            }

            pub fn limits(&self) -> &GenomeLimits {
                match self { $(Scene::$variant(s) => s.limits()),+ }
            }

            pub fn threshold(&self) -> f64 {
                match self { $(Scene::$variant(s) => s.threshold()),+ }
            }

            /// Edge length of one voxel at resolution `dims`, m.
            pub fn voxel_size(&self, dims: GridDims) -> f64 {
                match self { $(Scene::$variant(s) => s.voxel_size(dims)),+ }
            }

            pub fn check_dims(&self, dims: GridDims) -> Result<(), ResolutionError> {
                match self { $(Scene::$variant(s) => s.check_dims(dims)),+ }
            }

            /// The voxels a genome makes at `dims`, after the task keeps what it can use.
            pub fn design(&self, genome: &Genome, dims: GridDims) -> VoxelGrid {
                match self { $(Scene::$variant(s) => design(s, genome, dims)),+ }
            }

            /// Evaluates `genome` at resolution `dims`: pure and deterministic. A panic inside
            /// (a bug of ours) becomes an `Internal` failure, so one design never brings a worker
            /// or a run down.
            pub fn evaluate(&self, genome: &Genome, dims: GridDims) -> Outcome {
                catch_unwind(AssertUnwindSafe(|| match self {
                    $(Scene::$variant(s) => evaluate_task(s, genome, dims).map(Metrics::$variant)),+
                }))
                .unwrap_or_else(|panic| {
                    let message = panic
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| panic.downcast_ref::<String>().cloned())
                        .unwrap_or_else(|| "unknown panic".into());
                    Outcome::failed(Failure::Internal(message))
                })
            }

            /// Peak memory of an evaluation per voxel, bytes (see [`Task::BYTES_PER_VOXEL`]).
            pub fn bytes_per_voxel(&self) -> u64 {
                match self { $(Scene::$variant(_) => <$scene as Task>::BYTES_PER_VOXEL),+ }
            }

            /// The figure history and progress plots follow for this task.
            pub fn figure_spec(&self) -> Figure {
                match self { $(Scene::$variant(_) => <$scene as Task>::FIGURE),+ }
            }

            /// Whether `outcome` is one this scene can produce at `dims` (see
            /// [`Task::check_metrics`]); a failure always is.
            pub fn check_outcome(
                &self,
                outcome: &Outcome,
                dims: GridDims,
            ) -> Result<(), ImplausibleClaim> {
                let Outcome::Evaluated { fitness, metrics } = outcome else { return Ok(()) };
                if !fitness.is_finite() {
                    return Err(error::implausible!("fitness {fitness} is not finite"));
                }
                match (self, metrics) {
                    $((Scene::$variant(s), Metrics::$variant(m)) => s.check_metrics(*fitness, m, dims),)+
                    #[allow(unreachable_patterns)]
                    _ => Err(error::implausible!("metrics of another task for a {} scene", self.kind())),
                }
            }

            /// The objectives a multi-objective search may trade off on this task.
            pub fn objectives(&self) -> &'static [Objective] {
                match self { $(Scene::$variant(_) => <$scene as Task>::OBJECTIVES),+ }
            }

            /// The objectives' values for an outcome evaluated at `dims`, in their order
            /// (`None` for a failure).
            pub fn objective_values(&self, outcome: &Outcome, dims: GridDims) -> Option<Vec<f64>> {
                match (self, outcome.metrics()?) {
                    $((Scene::$variant(s), Metrics::$variant(m)) => Some(s.objective_values(m, dims)),)+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            /// The task's one-line headline of an outcome (`None` for a failure).
            pub fn headline(&self, outcome: &Outcome) -> Option<String> {
                match (self, outcome.metrics()?) {
                    $((Scene::$variant(s), Metrics::$variant(m)) => Some(s.headline(m)),)+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            /// The task's figure of an outcome (`None` for a failure).
            pub fn figure(&self, outcome: &Outcome) -> Option<f64> {
                match (self, outcome.metrics()?) {
                    $((Scene::$variant(s), Metrics::$variant(m)) => Some(s.figure(m)),)+
                    #[allow(unreachable_patterns)]
                    _ => None,
                }
            }

            /// Whether the task has a stop target (`budget.target_rms_percent`).
            pub fn has_target(&self) -> bool {
                match self { $(Scene::$variant(_) => <$scene as Task>::HAS_TARGET),+ }
            }

            /// The stop rule: whether `outcome` meets `target` (false for a failure).
            pub fn meets_target(&self, outcome: &Outcome, target: f64) -> bool {
                let Some(metrics) = outcome.metrics() else { return false };
                match (self, metrics) {
                    $((Scene::$variant(s), Metrics::$variant(m)) => s.meets_target(m, target),)+
                    #[allow(unreachable_patterns)]
                    _ => false,
                }
            }

            /// The task's fields of `summary.json` for its best outcome.
            pub fn summary(&self, best: &Outcome) -> serde_json::Value {
                match self {
                    $(Scene::$variant(s) => {
                        let m = match best.metrics() { Some(Metrics::$variant(m)) => Some(m), _ => None };
                        s.summary(m)
                    }),+
                }
            }

            /// The report's heading and table for the best outcome at `dims`.
            pub fn table(&self, best: &Outcome, dims: GridDims) -> (String, Block) {
                match self {
                    $(Scene::$variant(s) => {
                        let m = match best.metrics() { Some(Metrics::$variant(m)) => Some(m), _ => None };
                        s.table(m, dims)
                    }),+
                }
            }

            /// The task's own pictures and data files of the best design (none for a failure).
            pub fn write_artefacts(
                &self,
                dir: &Path,
                genome: &Genome,
                dims: GridDims,
                best: &Outcome,
            ) -> std::io::Result<Vec<Artefact>> {
                match (self, best.metrics()) {
                    $((Scene::$variant(s), Some(Metrics::$variant(m))) => s.write_artefacts(dir, genome, dims, m),)+
                    _ => Ok(Vec::new()),
                }
            }

            /// How another simulator runs a design at `dims` (for VXA exports), with the
            /// design's own settings where its outcome `of` is given (see
            /// [`Task::simulator_settings`]).
            pub fn simulator_settings(&self, dims: GridDims, of: Option<&Outcome>) -> Option<SimulatorSettings> {
                match self {
                    $(Scene::$variant(s) => {
                        let m = match of.and_then(Outcome::metrics) { Some(Metrics::$variant(m)) => Some(m), _ => None };
                        s.simulator_settings(dims, m)
                    }),+
                }
            }
        }
    };
}

tasks! {
    Beam = "beam" => beam::BeamScene,
    Locomotion = "locomotion" => locomotion::LocomotionScene,
    Stiffness = "stiffness" => stiffness::StiffnessScene,
}
