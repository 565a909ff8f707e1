//! Test fixtures for the search's unit tests: individuals with a chosen fitness and genomes with
//! points where a test wants them.

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::outcome::Failure;
use amorph::task::beam::BeamMetrics;
use amorph::task::{Metrics, Outcome};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::island::{Individual, Island};
use crate::ids::{IslandId, TaskId};

/// An evaluated beam outcome with this fitness (the metrics are placeholders no rule reads).
pub fn scored(fitness: f64) -> Outcome {
    Outcome::evaluated(
        fitness,
        Metrics::Beam(BeamMetrics {
            rms_percent: (-fitness).max(0.0).sqrt(),
            tip_deflection: 1e-3,
            voxels: 1,
            material_counts: vec![1],
            surface_voxels: 1,
            profile: Vec::new(),
            solver_iterations: 0,
            solver_residual: 0.0,
        }),
    )
}

pub fn failed() -> Outcome {
    Outcome::failed(Failure::Empty)
}

/// A genome of one point at `x` along the first axis (so genome distance is |x - x'|).
pub fn point_at(x: f64) -> Genome {
    points_at(&[x])
}

/// A genome of one point at each of `xs` along the first axis, each of density 0.5 and falloff
/// 0.1.
pub fn points_at(xs: &[f64]) -> Genome {
    Genome::new(
        (xs.iter())
            .map(|&x| GaussianPoint {
                position: [x, 0.5, 0.5],
                density: 0.5,
                falloff: 0.1,
                material: MaterialId(0),
            })
            .collect(),
    )
}

/// An island whose slot i holds a one-point genome at `xs[i]` scored `fitness[i]`, with task ids
/// `100 * island + i` so a test can tell where an individual came from.
pub fn island(id: u32, xs: &[f64], fitness: &[f64]) -> Island {
    let population = xs
        .iter()
        .zip(fitness)
        .enumerate()
        .map(|(i, (&x, &f))| Individual {
            genome: point_at(x),
            outcome: scored(f),
            task: TaskId(100 * u64::from(id) + i as u64),
        })
        .collect();
    Island::from_evaluated(
        IslandId(id),
        ChaCha8Rng::seed_from_u64(u64::from(id)),
        population,
    )
}
