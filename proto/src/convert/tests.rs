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
            reason: DivergenceReason::NonFinite,
            time: 0.125,
        }),
        Outcome::failed(Failure::Diverged {
            reason: DivergenceReason::Strain {
                strain: 1.000_000_000_000_000_2,
                limit: 1.0,
            },
            time: 2.5e-3,
        }),
        Outcome::failed(Failure::Diverged {
            reason: DivergenceReason::Runaway {
                travel: 0.3,
                limit: 0.25,
            },
            time: 1.0,
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
            divergence: None,
        })),
    };
    assert!(outcome_from_wire(&unknown).is_err());
    let diverged = |divergence| v1::Outcome {
        result: Some(v1::outcome::Result::Failed(v1::Failed {
            kind: v1::FailureKind::Diverged as i32,
            message: String::new(),
            time: 0.5,
            divergence,
        })),
    };
    let err = outcome_from_wire(&diverged(None)).unwrap_err().to_string();
    assert!(err.contains("outcome.failed.divergence"), "{err}");
    let strain = |kind: v1::DivergenceKind, value: f64| {
        diverged(Some(v1::Divergence {
            kind: kind as i32,
            value,
            limit: 1.0,
        }))
    };
    let err = outcome_from_wire(&strain(v1::DivergenceKind::Strain, f64::NAN))
        .unwrap_err()
        .to_string();
    assert!(err.contains("outcome.failed.divergence.value"), "{err}");
    let err = outcome_from_wire(&strain(v1::DivergenceKind::Unspecified, 2.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("outcome.failed.divergence.kind"), "{err}");
    assert!(outcome_from_wire(&v1::Outcome { result: None }).is_err());
}
