//! The edge between wire and domain: every message a peer sends is checked here (sizes, ranges,
//! finite numbers) and turned into the shared library's types, so the coordinator's and the worker's
//! cores never see a prost type nor a value they did not validate. Errors name the field.

use amorph::dynamics::DivergenceReason;
use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::outcome::Failure;
use amorph::task::Scene;
use amorph::task::{Metrics, Outcome};
use amorph::voxel::GridDims;

use crate::v1;

/// Most Gaussian points a genome may carry on the wire, whatever the scene allows; a scene's own
/// (smaller) limit is enforced by the evaluation, which returns an invalid-genome outcome.
pub const MAX_GENOME_POINTS: usize = 65_536;

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum WireError {
    #[error("{field} is missing")]
    Missing { field: &'static str },
    #[error("{field} = {value} is not finite")]
    NotFinite { field: String, value: f64 },
    #[error("{field} = {value} is out of range ({range})")]
    OutOfRange {
        field: String,
        value: String,
        range: &'static str,
    },
    #[error("{field}: {source}")]
    Grid {
        field: &'static str,
        source: crate::grid::GridSizeError,
    },
    #[error("{field}: {message}")]
    Malformed {
        field: &'static str,
        message: String,
    },
}

type Result<T> = std::result::Result<T, WireError>;

pub fn genome_to_wire(genome: &Genome) -> v1::Genome {
    v1::Genome {
        points: genome
            .points
            .iter()
            .map(|p| v1::GaussianPoint {
                x: p.position[0],
                y: p.position[1],
                z: p.position[2],
                density: p.density,
                falloff: p.falloff,
                material: u32::from(p.material.0),
            })
            .collect(),
    }
}

/// A wire genome as a domain genome: finite numbers, positions in the unit cube, positive
/// falloff, a material index that fits, and at most [`MAX_GENOME_POINTS`] points.
pub fn genome_from_wire(genome: &v1::Genome) -> Result<Genome> {
    if genome.points.len() > MAX_GENOME_POINTS {
        return Err(WireError::OutOfRange {
            field: "genome.points".into(),
            value: genome.points.len().to_string(),
            range: "at most 65536 points",
        });
    }
    let points = genome
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let finite = |name: &str, value: f64| {
                if value.is_finite() {
                    Ok(value)
                } else {
                    Err(WireError::NotFinite {
                        field: format!("genome.points[{i}].{name}"),
                        value,
                    })
                }
            };
            let unit = |name: &str, value: f64| {
                let value = finite(name, value)?;
                if (0.0..=1.0).contains(&value) {
                    Ok(value)
                } else {
                    Err(WireError::OutOfRange {
                        field: format!("genome.points[{i}].{name}"),
                        value: value.to_string(),
                        range: "[0, 1]",
                    })
                }
            };
            let falloff = finite("falloff", p.falloff)?;
            if falloff <= 0.0 {
                return Err(WireError::OutOfRange {
                    field: format!("genome.points[{i}].falloff"),
                    value: falloff.to_string(),
                    range: "> 0",
                });
            }
            let material = u8::try_from(p.material).map_err(|_| WireError::OutOfRange {
                field: format!("genome.points[{i}].material"),
                value: p.material.to_string(),
                range: "0..=255",
            })?;
            Ok(GaussianPoint {
                position: [unit("x", p.x)?, unit("y", p.y)?, unit("z", p.z)?],
                density: finite("density", p.density)?,
                falloff,
                material: MaterialId(material),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Genome::new(points))
}

pub fn dims_to_wire(dims: GridDims) -> v1::Resolution {
    let count = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
    v1::Resolution {
        nx: count(dims.nx),
        ny: count(dims.ny),
        nz: count(dims.nz),
    }
}

/// A resolution within the grid limits (`crate::grid`).
pub fn dims_from_wire(resolution: Option<&v1::Resolution>) -> Result<GridDims> {
    let r = resolution.ok_or(WireError::Missing {
        field: "task.resolution",
    })?;
    crate::grid::checked_grid([r.nx, r.ny, r.nz].map(u64::from)).map_err(|source| WireError::Grid {
        field: "task.resolution",
        source,
    })
}

pub fn outcome_to_wire(outcome: &Outcome) -> v1::Outcome {
    use v1::outcome::Result as R;
    let result = match outcome {
        Outcome::Evaluated { fitness, metrics } => R::Evaluated(v1::Evaluated {
            fitness: *fitness,
            metrics_json: serde_json::to_vec(metrics).expect("metrics serialize"),
        }),
        Outcome::Failed { failure } => {
            let (kind, message, time) = match failure {
                Failure::InvalidGenome(m) => (v1::FailureKind::InvalidGenome, m.clone(), 0.0),
                Failure::InvalidRequest(m) => (v1::FailureKind::InvalidRequest, m.clone(), 0.0),
                Failure::Empty => (v1::FailureKind::Empty, String::new(), 0.0),
                Failure::NotSpanning => (v1::FailureKind::NotSpanning, String::new(), 0.0),
                Failure::Solver(m) => (v1::FailureKind::Solver, m.clone(), 0.0),
                Failure::Degenerate(m) => (v1::FailureKind::Degenerate, m.clone(), 0.0),
                Failure::Internal(m) => (v1::FailureKind::Internal, m.clone(), 0.0),
                Failure::Diverged { time, .. } => (v1::FailureKind::Diverged, String::new(), *time),
            };
            let divergence = match failure {
                Failure::Diverged { reason, .. } => Some(divergence_to_wire(reason)),
                _ => None,
            };
            R::Failed(v1::Failed {
                kind: kind as i32,
                message,
                time,
                divergence,
            })
        }
    };
    v1::Outcome {
        result: Some(result),
    }
}

/// A reported outcome as a domain outcome: a finite fitness and metrics that parse, or a failure
/// of a known kind. Exact: `outcome_from_wire(&outcome_to_wire(o)) == o`, bit for bit.
pub fn outcome_from_wire(outcome: &v1::Outcome) -> Result<Outcome> {
    use v1::outcome::Result as R;
    match outcome.result.as_ref() {
        None => Err(WireError::Missing {
            field: "outcome.result",
        }),
        Some(R::Evaluated(e)) => {
            if !e.fitness.is_finite() {
                return Err(WireError::NotFinite {
                    field: "outcome.evaluated.fitness".into(),
                    value: e.fitness,
                });
            }
            let metrics: Metrics =
                serde_json::from_slice(&e.metrics_json).map_err(|err| WireError::Malformed {
                    field: "outcome.evaluated.metrics_json",
                    message: err.to_string(),
                })?;
            Ok(Outcome::Evaluated {
                fitness: e.fitness,
                metrics,
            })
        }
        Some(R::Failed(f)) => {
            let kind = v1::FailureKind::try_from(f.kind).unwrap_or(v1::FailureKind::Unspecified);
            let m = f.message.clone();
            let failure = match kind {
                v1::FailureKind::Unspecified => {
                    return Err(WireError::OutOfRange {
                        field: "outcome.failed.kind".into(),
                        value: f.kind.to_string(),
                        range: "a known failure kind",
                    });
                }
                v1::FailureKind::InvalidGenome => Failure::InvalidGenome(m),
                v1::FailureKind::InvalidRequest => Failure::InvalidRequest(m),
                v1::FailureKind::Empty => Failure::Empty,
                v1::FailureKind::NotSpanning => Failure::NotSpanning,
                v1::FailureKind::Solver => Failure::Solver(m),
                v1::FailureKind::Degenerate => Failure::Degenerate(m),
                v1::FailureKind::Internal => Failure::Internal(m),
                v1::FailureKind::Diverged => {
                    if !f.time.is_finite() {
                        return Err(WireError::NotFinite {
                            field: "outcome.failed.time".into(),
                            value: f.time,
                        });
                    }
                    let reason = f.divergence.as_ref().ok_or(WireError::Missing {
                        field: "outcome.failed.divergence",
                    })?;
                    Failure::Diverged {
                        reason: divergence_from_wire(reason)?,
                        time: f.time,
                    }
                }
            };
            Ok(Outcome::Failed { failure })
        }
    }
}

fn divergence_to_wire(reason: &DivergenceReason) -> v1::Divergence {
    let (kind, value, limit) = match *reason {
        DivergenceReason::NonFinite => (v1::DivergenceKind::NonFinite, 0.0, 0.0),
        DivergenceReason::Strain { strain, limit } => (v1::DivergenceKind::Strain, strain, limit),
        DivergenceReason::Runaway { travel, limit } => (v1::DivergenceKind::Runaway, travel, limit),
    };
    v1::Divergence {
        kind: kind as i32,
        value,
        limit,
    }
}

fn divergence_from_wire(d: &v1::Divergence) -> Result<DivergenceReason> {
    for (field, value) in [
        ("outcome.failed.divergence.value", d.value),
        ("outcome.failed.divergence.limit", d.limit),
    ] {
        if !value.is_finite() {
            return Err(WireError::NotFinite {
                field: field.into(),
                value,
            });
        }
    }
    match v1::DivergenceKind::try_from(d.kind).unwrap_or(v1::DivergenceKind::Unspecified) {
        v1::DivergenceKind::NonFinite => Ok(DivergenceReason::NonFinite),
        v1::DivergenceKind::Strain => Ok(DivergenceReason::Strain {
            strain: d.value,
            limit: d.limit,
        }),
        v1::DivergenceKind::Runaway => Ok(DivergenceReason::Runaway {
            travel: d.value,
            limit: d.limit,
        }),
        v1::DivergenceKind::Unspecified => Err(WireError::OutOfRange {
            field: "outcome.failed.divergence.kind".into(),
            value: d.kind.to_string(),
            range: "a known divergence kind",
        }),
    }
}

pub fn scene_to_wire(scene: &Scene) -> Vec<u8> {
    serde_json::to_vec(scene).expect("scenes serialize")
}

/// A fetched scene, parsed and validated.
pub fn scene_from_wire(json: &[u8]) -> Result<Scene> {
    let scene: Scene = serde_json::from_slice(json).map_err(|e| WireError::Malformed {
        field: "scene_json",
        message: e.to_string(),
    })?;
    scene.validate().map_err(|e| WireError::Malformed {
        field: "scene_json",
        message: e.to_string(),
    })?;
    Ok(scene)
}

/// The content id of a scene: a hash of its canonical JSON, so a worker's cache can never serve
/// a stale scene under a reused id. FNV-1a (64 bit) is enough: ids name, they do not authenticate.
pub fn scene_id(scene: &Scene) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in scene_to_wire(scene) {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("scene-{hash:016x}")
}

#[cfg(test)]
mod tests;
