//! The edge between wire and domain: every message a peer sends is checked here (sizes, ranges,
//! finite numbers) and turned into the shared library's types, so the coordinator's and the worker's
//! cores never see a prost type nor a value they did not validate. Errors name the field.

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
                Failure::Diverged { reason, time } => {
                    (v1::FailureKind::Diverged, reason.clone(), *time)
                }
            };
            R::Failed(v1::Failed {
                kind: kind as i32,
                message,
                time,
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
                    Failure::Diverged {
                        reason: m,
                        time: f.time,
                    }
                }
            };
            Ok(Outcome::Failed { failure })
        }
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
mod tests {
    use super::*;
    use amorph::task::beam::BeamMetrics;

    fn genome() -> Genome {
        Genome::new(vec![GaussianPoint {
            position: [0.1, 0.5, 1.0],
            density: -0.3,
            falloff: 0.05,
            material: MaterialId(1),
        }])
    }

    #[test]
    fn genomes_round_trip_exactly() {
        let g = genome();
        assert_eq!(genome_from_wire(&genome_to_wire(&g)).unwrap(), g);
    }

    #[test]
    fn a_nan_genome_is_refused_naming_the_field() {
        let mut wire = genome_to_wire(&genome());
        wire.points[0].density = f64::NAN;
        let err = genome_from_wire(&wire).unwrap_err().to_string();
        assert!(err.contains("genome.points[0].density"), "{err}");
        let mut wire = genome_to_wire(&genome());
        wire.points[0].y = 1.5;
        let err = genome_from_wire(&wire).unwrap_err().to_string();
        assert!(err.contains("genome.points[0].y"), "{err}");
        let mut wire = genome_to_wire(&genome());
        wire.points[0].material = 300;
        assert!(genome_from_wire(&wire).is_err());
    }

    #[test]
    fn oversized_requests_are_refused() {
        let wire = v1::Genome {
            points: vec![genome_to_wire(&genome()).points[0]; MAX_GENOME_POINTS + 1],
        };
        assert!(genome_from_wire(&wire).is_err());
        let big = v1::Resolution {
            nx: 1024,
            ny: 1024,
            nz: 2,
        };
        let err = dims_from_wire(Some(&big)).unwrap_err().to_string();
        assert!(err.contains("task.resolution"), "{err}");
        let zero = v1::Resolution {
            nx: 0,
            ny: 4,
            nz: 4,
        };
        assert!(dims_from_wire(Some(&zero)).is_err());
        assert!(dims_from_wire(None).is_err());
        let ok = dims_to_wire(GridDims::new(12, 40, 12));
        assert_eq!(
            dims_from_wire(Some(&ok)).unwrap(),
            GridDims::new(12, 40, 12)
        );
    }

    #[test]
    fn outcomes_round_trip_bit_for_bit() {
        let metrics = Metrics::Beam(BeamMetrics {
            rms_percent: 0.1 + 0.2,
            tip_deflection: 1e-3 / 3.0,
            voxels: 7,
            material_counts: vec![3, 4],
            surface_voxels: 2,
            profile: vec![[0.5, std::f64::consts::PI, -0.0]],
            solver_iterations: 18,
            solver_residual: 4e-10,
        });
        let outcomes = [
            Outcome::Evaluated {
                fitness: -1.234_567_890_123_456_7e-5,
                metrics,
            },
            Outcome::failed(Failure::Empty),
            Outcome::failed(Failure::Diverged {
                reason: "energy".into(),
                time: 0.125,
            }),
            Outcome::failed(Failure::InvalidGenome("point 3".into())),
        ];
        for o in outcomes {
            assert_eq!(outcome_from_wire(&outcome_to_wire(&o)).unwrap(), o);
        }
    }

    #[test]
    fn malformed_outcomes_are_refused() {
        let nan = v1::Outcome {
            result: Some(v1::outcome::Result::Evaluated(v1::Evaluated {
                fitness: f64::NAN,
                metrics_json: b"{}".to_vec(),
            })),
        };
        assert!(outcome_from_wire(&nan).is_err());
        let garbage = v1::Outcome {
            result: Some(v1::outcome::Result::Evaluated(v1::Evaluated {
                fitness: 1.0,
                metrics_json: b"not json".to_vec(),
            })),
        };
        let err = outcome_from_wire(&garbage).unwrap_err().to_string();
        assert!(err.contains("metrics_json"), "{err}");
        let unknown = v1::Outcome {
            result: Some(v1::outcome::Result::Failed(v1::Failed {
                kind: 99,
                message: String::new(),
                time: 0.0,
            })),
        };
        assert!(outcome_from_wire(&unknown).is_err());
        assert!(outcome_from_wire(&v1::Outcome { result: None }).is_err());
    }
}
