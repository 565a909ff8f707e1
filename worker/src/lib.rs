//! The Amorph worker: stateless evaluation of genomes. `worker --connect URL` pulls tasks from a
//! coordinator over gRPC ([`client`]) and evaluates them on a CPU pool ([`pool`]); `worker evaluate`
//! and `worker export` do the same evaluation offline for a saved genome.

pub mod client;
pub mod pool;

pub use client::{ClientError, WorkerOptions, WorkerSummary, run_worker};
pub use pool::EvaluationMode;

/// Resolves at the first Ctrl-C or SIGTERM (how a terminal, docker, Kubernetes and Slurm all ask a
/// process to stop).
pub async fn termination() {
    let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()).ok();
    let terminated = async {
        match term.as_mut() {
            Some(t) => {
                t.recv().await;
            }
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        _ = tokio::signal::ctrl_c() => {}
        _ = terminated => {}
    }
}

use std::path::Path;

use amorph::genome::Genome;
use amorph::task::Scene;
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
}

pub type Result<T> = std::result::Result<T, WorkerError>;

/// A genome file: either a bare genome or any results file holding one under `genome`
/// (`best_genome.json`, `island-<i>-best.json`).
#[derive(Deserialize)]
#[serde(untagged)]
enum GenomeFile {
    Bare(Genome),
    Wrapped { genome: Genome },
}

pub fn read_genome(path: &Path) -> Result<Genome> {
    let text = read(path)?;
    let file: GenomeFile = serde_json::from_str(&text).map_err(|e| WorkerError::Parse {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    Ok(match file {
        GenomeFile::Bare(g) | GenomeFile::Wrapped { genome: g } => g,
    })
}

/// A scene from a TOML file: a run config (its `[scene]` table is used) or a bare scene table.
pub fn read_scene(path: &Path) -> Result<Scene> {
    #[derive(Deserialize)]
    struct WithScene {
        scene: Scene,
    }
    let text = read(path)?;
    let parse_error = |message: String| WorkerError::Parse {
        path: path.display().to_string(),
        message,
    };
    let value: toml::Table =
        toml::from_str(&text).map_err(|e| parse_error(e.message().to_owned()))?;
    let scene = if value.contains_key("scene") {
        value
            .try_into::<WithScene>()
            .map(|w| w.scene)
            .map_err(|e| parse_error(e.message().to_owned()))?
    } else {
        value
            .try_into::<Scene>()
            .map_err(|e| parse_error(e.message().to_owned()))?
    };
    let mut scene = scene;
    scene
        .load_files(path.parent().unwrap_or(Path::new(".")))
        .map_err(|e| parse_error(format!("scene.{e}")))?;
    scene
        .validate()
        .map_err(|e| parse_error(format!("scene.{e}")))?;
    Ok(scene)
}

/// Parses `12x12x40`.
pub fn parse_resolution(text: &str) -> Result<GridDims> {
    let counts: Vec<usize> = text
        .split('x')
        .map(|p| p.trim().parse().ok().filter(|&n| n > 0))
        .collect::<Option<_>>()
        .ok_or_else(|| WorkerError::Resolution(text.to_owned()))?;
    match counts[..] {
        [nx, ny, nz] => Ok(GridDims::new(nx, ny, nz)),
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
mod tests {
    use super::*;

    #[test]
    fn resolutions_parse_strictly() {
        assert_eq!(
            parse_resolution("12x12x40").unwrap(),
            GridDims::new(12, 12, 40)
        );
        for bad in ["12x12", "0x1x1", "axbxc", "1x2x3x4", ""] {
            assert!(parse_resolution(bad).is_err(), "{bad}");
        }
    }
}
