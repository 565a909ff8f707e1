//! The run configuration: a TOML file read strictly (unknown keys are errors), with command-line
//! overrides (`--set`) and its search preset laid under it, validated into a [`RunConfig`] before
//! anything runs. Every error is one line naming the key.

mod export;
mod overrides;
mod preset;

pub use overrides::Override;
pub use preset::Preset;

use std::path::{Path, PathBuf};

use amorph::genome::MutationParams;
use amorph::task::Scene;
use amorph::task::scene_toml::{self, SceneAt};
use serde::{Deserialize, Serialize};

pub use crate::cluster::settings::ClusterSection;
use crate::cluster::settings::ClusterSettings;
pub use crate::dashboard::DashboardSection;
use crate::search::{LocalSearchParams, MigrationParams, ResolutionSchedule, Selection};
pub use export::ExportSection;

#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read config {path}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("config {path}, line {line}: {message}")]
    Parse {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("config {path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error("config {path}: {message}")]
    Override { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, ConfigError>;

/// The file as written: every section and key, with defaults for what may be left out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawConfig {
    /// Name of the run; results go to `<results_dir>/<name>/`.
    pub name: String,
    /// The one seed every random choice of the run derives from.
    #[serde(default)]
    pub seed: u64,
    /// Folder that receives one sub-folder per run.
    #[serde(default = "default_results_dir")]
    pub results_dir: PathBuf,
    #[serde(default)]
    pub cluster: ClusterSection,
    #[serde(default)]
    pub search: SearchSection,
    #[serde(default)]
    pub budget: BudgetSection,
    /// End-of-run exports beyond the fabrication files (slice stack, finer-resolution check).
    #[serde(default)]
    pub export: ExportSection,
    /// The live dashboard, served while the run goes.
    #[serde(default, skip_serializing_if = "DashboardSection::is_default")]
    pub dashboard: DashboardSection,
    pub resolution: ResolutionSchedule,
    pub scene: Scene,
}

fn default_results_dir() -> PathBuf {
    PathBuf::from("results")
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SearchSection {
    /// The defaults of the search keys a config leaves out ([`Preset`]); every key here and in
    /// `local_search`, and `resolution`'s stall rule, may come from it.
    pub preset: Preset,
    /// Individuals per island (paper: 50).
    pub population: usize,
    /// Number of islands.
    pub islands: usize,
    /// Children each island breeds per epoch (evaluated in parallel).
    pub children_per_epoch: usize,
    /// Children whose design at the level's resolution is their dominant parent's are not
    /// evaluated: they could not replace it, so the run breeds and replaces exactly as without
    /// the key, on fewer evaluations (`search::unchanged`). The paper evaluates every child.
    pub skip_unchanged: bool,
    /// Gaussian points in each initial random genome.
    pub initial_points: usize,
    pub mutation: MutationParams,
    pub migration: MigrationParams,
    /// Nudges of the best design (off in the paper's search).
    pub local_search: LocalSearchParams,
    /// The task's objectives a run trades off (names from `Scene::objectives`); none: the task's
    /// single fitness.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub objectives: Vec<String>,
    /// How an island of a multi-objective run keeps its population.
    #[serde(skip_serializing_if = "Selection::is_default")]
    pub selection: Selection,
    /// The point the hypervolume is measured from, one value per objective in the task's units:
    /// a design counts only where it is better than it in every objective.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub hypervolume_reference: Vec<f64>,
}

impl Default for SearchSection {
    fn default() -> Self {
        Self {
            preset: Preset::Paper,
            population: 50,
            islands: 1,
            children_per_epoch: 50,
            skip_unchanged: false,
            initial_points: 40,
            mutation: MutationParams::default(),
            migration: MigrationParams::default(),
            local_search: LocalSearchParams::default(),
            objectives: Vec::new(),
            selection: Selection::default(),
            hypervolume_reference: Vec::new(),
        }
    }
}

/// When to stop; the first limit reached ends the run. At least one must be set.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BudgetSection {
    /// Total evaluations, including the initial population and re-evaluations at a new resolution.
    pub evaluations: Option<u64>,
    /// Wall-clock seconds (the one limit that depends on machine speed).
    pub wall_seconds: Option<f64>,
    /// Stop once the best design's RMS error (beam task, finest resolution) is at most this, %.
    pub target_rms_percent: Option<f64>,
}

/// A validated configuration: what [`crate::run`] accepts. Its sections are the file's, checked
/// as a whole ([`RunConfig::try_from_raw`]); [`RunConfig::to_raw`] gives the document a run
/// records, every default and preset value written out.
#[derive(Clone, Debug, PartialEq)]
pub struct RunConfig {
    pub name: String,
    pub seed: u64,
    pub results_dir: PathBuf,
    pub cluster: ClusterSection,
    pub search: SearchSection,
    pub budget: BudgetSection,
    pub export: ExportSection,
    pub dashboard: DashboardSection,
    pub resolution: ResolutionSchedule,
    pub scene: Scene,
    /// Where this config came from, for messages.
    pub source: PathBuf,
}

/// The quickstart, compiled in: what `coordinator` runs without `--config`.
pub const QUICKSTART: &str = include_str!("../../configs/quickstart.toml");

impl RunConfig {
    /// Reads, parses and validates a config file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::load_with(path, &[])
    }

    /// Reads a config file and applies `overrides` (`--set`) before validating it.
    pub fn load_with(path: &Path, overrides: &[Override]) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse_with(&text, path, overrides)
    }

    /// The embedded quickstart with `overrides`; its path names it in messages and is where a
    /// custom profile's file would be looked for.
    pub fn quickstart(overrides: &[Override]) -> Result<Self> {
        Self::parse_with(QUICKSTART, Path::new("configs/quickstart.toml"), overrides)
    }

    /// Parses and validates config text; `path` only names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        Self::parse_with(text, path, &[])
    }

    /// Parses config text, applies `overrides` in order, lays the search preset under the result
    /// and validates it. Errors in the text name its line; an override that breaks the config is
    /// named by its `--set`.
    pub fn parse_with(text: &str, path: &Path, overrides: &[Override]) -> Result<Self> {
        let parse_error = |text: &str, e: toml::de::Error| {
            let e = scene_toml::relocate(text, SceneAt::Config, &e).unwrap_or(e);
            let (line, message) = scene_toml::locate(text, &e);
            ConfigError::Parse {
                path: path.to_owned(),
                line,
                message,
            }
        };
        // The file alone first, so that its own mistakes are named by their line.
        toml::from_str::<RawConfig>(text).map_err(|e| parse_error(text, e))?;
        let mut document: toml::Table = text.parse().map_err(|e| parse_error(text, e))?;
        for set in overrides {
            let refused = |message: String| ConfigError::Override {
                path: path.to_owned(),
                message,
            };
            set.apply(&mut document).map_err(refused)?;
            let written = toml::to_string(&document).map_err(|e| refused(e.to_string()))?;
            toml::from_str::<RawConfig>(&written).map_err(|e| {
                let e = scene_toml::relocate(&written, SceneAt::Config, &e).unwrap_or(e);
                refused(format!(
                    "--set {}: {}",
                    set.text,
                    e.message().replace('\n', " ")
                ))
            })?;
        }
        // The document parsed as a config above (the file alone, then after each override), so
        // its preset and scene kind read without another pass through the whole config.
        let preset = match document.get("search").and_then(|s| s.get("preset")) {
            Some(named) => named.clone().try_into().expect("checked above"),
            None => Preset::for_run(
                (document["scene"].get("kind").and_then(toml::Value::as_str))
                    .expect("checked above"),
                (document.get("search").and_then(|s| s.get("objectives")))
                    .and_then(toml::Value::as_array)
                    .is_some_and(|o| !o.is_empty()),
            ),
        };
        preset::lay_under(&mut document, preset.defaults());
        let raw = toml::from_str(&toml::to_string(&document).expect("a TOML table")).map_err(
            |e: toml::de::Error| ConfigError::Invalid {
                path: path.to_owned(),
                message: format!("the {} preset: {}", preset.key(), e.message()),
            },
        )?;
        Self::try_from_raw(raw, path)
    }

    /// Validates a parsed config; files the scene names (a custom profile's CSV) are read
    /// relative to `path`'s folder and kept in the scene.
    pub fn try_from_raw(mut raw: RawConfig, path: &Path) -> Result<Self> {
        let invalid = |message: String| ConfigError::Invalid {
            path: path.to_owned(),
            message,
        };
        let base = path.parent().unwrap_or(Path::new("."));
        raw.scene
            .load_files(base)
            .map_err(|e| invalid(format!("scene.{e}")))?;
        validate(&raw).map_err(invalid)?;
        let RawConfig {
            name,
            seed,
            results_dir,
            cluster,
            search,
            budget,
            export,
            dashboard,
            resolution,
            scene,
        } = raw;
        Ok(Self {
            name,
            seed,
            results_dir,
            cluster,
            search,
            budget,
            export,
            dashboard,
            resolution,
            scene,
            source: path.to_owned(),
        })
    }

    /// The config as a run records it (config.toml, the run store).
    pub fn to_raw(&self) -> RawConfig {
        RawConfig {
            name: self.name.clone(),
            seed: self.seed,
            results_dir: self.results_dir.clone(),
            cluster: self.cluster.clone(),
            search: self.search.clone(),
            budget: self.budget.clone(),
            export: self.export.clone(),
            dashboard: self.dashboard.clone(),
            resolution: self.resolution.clone(),
            scene: self.scene.clone(),
        }
    }

    /// The folder this run writes its results into.
    pub fn run_dir(&self) -> PathBuf {
        self.results_dir.join(&self.name)
    }
}

/// Most individuals over all islands, and most islands: a million genomes of the paper's size
/// hold a few GB, and every bound keeps size arithmetic far from overflow.
const MAX_INDIVIDUALS: usize = 1 << 20;
const MAX_ISLANDS: usize = 4096;

fn validate(raw: &RawConfig) -> std::result::Result<(), String> {
    let s = &raw.search;
    if raw.name.is_empty() || raw.name.contains(['/', '\\']) || raw.name.starts_with('.') {
        return Err(format!("name = {:?} must be a plain folder name", raw.name));
    }
    if !(2..=MAX_INDIVIDUALS).contains(&s.population) {
        return Err(format!(
            "search.population = {} must be between 2 and {MAX_INDIVIDUALS}",
            s.population
        ));
    }
    if !(1..=MAX_ISLANDS).contains(&s.islands) {
        return Err(format!(
            "search.islands = {} must be between 1 and {MAX_ISLANDS}",
            s.islands
        ));
    }
    if !(1..=MAX_INDIVIDUALS).contains(&s.children_per_epoch) {
        return Err(format!(
            "search.children_per_epoch = {} must be between 1 and {MAX_INDIVIDUALS}",
            s.children_per_epoch
        ));
    }
    // Both bounded above, so the product is at most 2^32: no overflow.
    if s.islands * s.population > MAX_INDIVIDUALS {
        return Err(format!(
            "search.islands x search.population = {} x {} = {} individuals, at most {MAX_INDIVIDUALS}",
            s.islands,
            s.population,
            s.islands * s.population
        ));
    }
    if s.islands * s.children_per_epoch > MAX_INDIVIDUALS {
        return Err(format!(
            "search.islands x search.children_per_epoch = {} children per epoch, at most {MAX_INDIVIDUALS}",
            s.islands * s.children_per_epoch
        ));
    }
    let limits = raw.scene.limits();
    if s.initial_points == 0 || s.initial_points > limits.max_points {
        return Err(format!(
            "search.initial_points must be between 1 and scene.limits.max_points ({})",
            limits.max_points
        ));
    }
    s.mutation
        .validate()
        .map_err(|field| format!("search.mutation.{field} is out of range"))?;
    if let crate::search::Topology::Random { probability } = s.migration.topology
        && !(0.0..=1.0).contains(&probability)
    {
        return Err("search.migration.topology.probability must be in [0, 1]".into());
    }
    s.local_search.validate()?;
    validate_objectives(raw)?;
    let b = &raw.budget;
    if b.evaluations.is_none() && b.wall_seconds.is_none() && b.target_rms_percent.is_none() {
        return Err(
            "budget: set at least one of evaluations, wall_seconds, target_rms_percent".into(),
        );
    }
    let initial = (s.islands * s.population) as u64;
    if let Some(n) = b.evaluations
        && n < initial
    {
        return Err(format!(
            "budget.evaluations = {n} does not cover the initial populations ({} islands x {} individuals)",
            s.islands, s.population
        ));
    }
    if let Some(w) = b.wall_seconds
        && !(w.is_finite() && w > 0.0)
    {
        return Err("budget.wall_seconds must be a positive number".into());
    }
    if let Some(t) = b.target_rms_percent
        && !(t.is_finite() && t >= 0.0)
    {
        return Err("budget.target_rms_percent must be a non-negative number".into());
    }
    if b.target_rms_percent.is_some() && !raw.scene.has_target() {
        return Err(format!(
            "budget.target_rms_percent: a {} scene has no such target",
            raw.scene.kind()
        ));
    }
    ClusterSettings::try_from(&raw.cluster)?;
    raw.export.validate()?;
    raw.resolution.validate()?;
    raw.scene.validate().map_err(|e| format!("scene.{e}"))?;
    for (i, &[nx, ny, nz]) in raw.resolution.levels.iter().enumerate() {
        raw.scene
            .check_dims(amorph::voxel::GridDims::new(nx, ny, nz))
            .map_err(|e| format!("resolution.levels[{i}] = [{nx}, {ny}, {nz}]: {e}"))?;
    }
    Ok(())
}

/// The multi-objective keys: two or more of the task's objectives, once each, a reference point
/// with a finite value for each, and a search the objectives can drive (the climb and a stop
/// target judge the single fitness).
fn validate_objectives(raw: &RawConfig) -> std::result::Result<(), String> {
    let s = &raw.search;
    if s.objectives.is_empty() {
        if !s.selection.is_default() {
            return Err("search.selection needs search.objectives".into());
        }
        if !s.hypervolume_reference.is_empty() {
            return Err("search.hypervolume_reference needs search.objectives".into());
        }
        return Ok(());
    }
    let known: Vec<&str> = raw.scene.objectives().iter().map(|o| o.name).collect();
    for (i, name) in s.objectives.iter().enumerate() {
        if !known.contains(&name.as_str()) {
            return Err(format!(
                "search.objectives[{i}] = {name:?} is not an objective of a {} scene; it has {}",
                raw.scene.kind(),
                known.join(", ")
            ));
        }
        if s.objectives[..i].contains(name) {
            return Err(format!("search.objectives[{i}] = {name:?} is named twice"));
        }
    }
    if s.objectives.len() < 2 {
        return Err("search.objectives needs two or more objectives to trade off".into());
    }
    if s.hypervolume_reference.len() != s.objectives.len()
        || s.hypervolume_reference.iter().any(|v| !v.is_finite())
    {
        return Err(format!(
            "search.hypervolume_reference must hold one finite number per objective ({})",
            s.objectives.len()
        ));
    }
    if s.local_search.fraction > 0.0 {
        return Err(
            "search.local_search.fraction must be 0 with search.objectives: the climb follows the single fitness".into(),
        );
    }
    if raw.budget.target_rms_percent.is_some() {
        return Err("budget.target_rms_percent cannot stop a run with search.objectives".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests;
