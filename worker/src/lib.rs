//! The Amorph worker: stateless evaluation of genomes. `worker --connect URL` pulls tasks from a
//! coordinator over gRPC ([`client`]) and evaluates them on a CPU pool ([`pool`]); `worker evaluate`
//! and `worker export` do the same evaluation offline for a saved genome.

pub mod client;
pub mod export;
pub mod pool;
mod run_design;

pub use client::{ClientError, WorkerOptions, WorkerSummary, run_worker};
pub use pool::EvaluationMode;
pub use run_design::read_run_design;

use std::path::Path;

use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::task::scene_toml::{self, SceneAt};
use amorph::voxel::GridDims;
use serde::Deserialize;

#[derive(Debug, thiserror::Error)]
pub enum WorkerError {
    #[error("cannot read {path}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Parse { path: String, message: String },
    #[error("resolution '{0}' is not of the form NXxNYxNZ with positive counts")]
    Resolution(String),
    #[error("resolution '{0}': {1}")]
    ResolutionLimit(String, amorph_proto::grid::GridSizeError),
}

pub type Result<T> = std::result::Result<T, WorkerError>;

/// A genome file: either a bare genome (`{"points": [...]}`) or any results file holding one
/// under `genome` (`best_genome.json`, `island-<i>-best.json`). Errors name the field
/// (`genome.points[3].material`), not just a position in the text.
pub fn read_genome(path: &Path) -> Result<Genome> {
    parse_genome(&read(path)?, &path.display().to_string())
}

/// [`read_genome`] for text already read; `source` names it in errors.
pub fn parse_genome(text: &str, source: &str) -> Result<Genome> {
    let parse_error = |message: String| WorkerError::Parse {
        path: source.to_owned(),
        message,
    };
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        // JSON has no NaN or Infinity; serde_json only says "expected value" where one stands.
        let hint = if ["NaN", "Infinity"].iter().any(|w| text.contains(w)) {
            " (JSON has no NaN or Infinity: every number must be finite)"
        } else {
            ""
        };
        parse_error(format!("{e}{hint}"))
    })?;
    let (genome, prefix) = match value.get("genome") {
        Some(g) => (g, "genome"),
        None => (&value, "the genome"),
    };
    let points = genome
        .get("points")
        .and_then(serde_json::Value::as_array)
        .ok_or_else(|| parse_error(format!("{prefix}.points is missing or not a list")))?;
    for (i, point) in points.iter().enumerate() {
        for field in ["position", "density", "falloff", "material"] {
            let Some(v) = point.get(field) else {
                return Err(parse_error(format!(
                    "{prefix}.points[{i}].{field} is missing"
                )));
            };
            let checked = match field {
                "position" => <[f64; 3]>::deserialize(v).map(|_| ()),
                "material" => amorph::material::MaterialId::deserialize(v).map(|_| ()),
                _ => f64::deserialize(v).map(|_| ()),
            };
            checked.map_err(|e| parse_error(format!("{prefix}.points[{i}].{field} = {v}: {e}")))?;
        }
    }
    Genome::deserialize(genome).map_err(|e| parse_error(format!("{prefix}: {e}")))
}

/// A scene from a TOML file: a run config (its `[scene]` table is used) or a bare scene table.
pub fn read_scene(path: &Path) -> Result<Scene> {
    let text = read(path)?;
    let parse_error = |message: String| WorkerError::Parse {
        path: path.display().to_string(),
        message,
    };
    let document: toml::Table = toml::from_str(&text).map_err(|e| {
        let (line, message) = scene_toml::locate(&text, &e);
        parse_error(format!("line {line}: {message}"))
    })?;
    let at = if document.contains_key("scene") {
        SceneAt::Config
    } else {
        SceneAt::Document
    };
    let mut scene = scene_toml::scene_from_toml(&text, at).map_err(parse_error)?;
    scene
        .load_files(path.parent().unwrap_or(Path::new(".")))
        .map_err(|e| parse_error(format!("scene.{e}")))?;
    scene
        .validate()
        .map_err(|e| parse_error(format!("scene.{e}")))?;
    Ok(scene)
}

/// Parses `12x12x40`, within the grid limits every task obeys (`amorph_proto::grid`).
pub fn parse_resolution(text: &str) -> Result<GridDims> {
    let counts: Vec<u64> = text
        .split('x')
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()
        .ok_or_else(|| WorkerError::Resolution(text.to_owned()))?;
    match counts[..] {
        [nx, ny, nz] => amorph_proto::grid::checked_grid([nx, ny, nz])
            .map_err(|e| WorkerError::ResolutionLimit(text.to_owned(), e)),
        _ => Err(WorkerError::Resolution(text.to_owned())),
    }
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|source| WorkerError::Read {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests;
