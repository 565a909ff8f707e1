//! The beam's residuals (issue 13, `local_search.combine_by = "residuals"`): the terms whose
//! squares sum to its fitness, one per profile station after the clamp, each at its station.

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn beam(target: &str) -> Scene {
    toml::from_str(&format!("kind = \"beam\"\ntarget = \"{target}\"\n")).expect("a beam scene")
}

/// A chain of wide blobs from clamp to tip, of random materials and sizes, so it spans the beam
/// with an uneven profile.
fn beam_genome(rng: &mut ChaCha8Rng) -> Genome {
    let points = (0..12)
        .map(|i| GaussianPoint {
            position: [
                rng.random_range(0.3..0.7),
                i as f64 / 11.0,
                rng.random_range(0.3..0.7),
            ],
            density: rng.random_range(0.6..1.0),
            falloff: rng.random_range(0.15..0.3),
            material: MaterialId(rng.random_range(0..2u8)),
        })
        .collect();
    Genome { points }
}

#[test]
fn the_squares_of_the_residuals_sum_to_the_fitness_station_by_station() {
    let dims = GridDims::new(6, 20, 6);
    let mut evaluated = 0;
    for target in [
        "straight",
        "circular_arc",
        "discontinuous_slope",
        "polynomial4",
    ] {
        let scene = beam(target);
        assert!(scene.has_residuals());
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..6 {
            let genome = beam_genome(&mut rng);
            let Outcome::Evaluated { fitness, metrics } = scene.evaluate(&genome, dims) else {
                continue;
            };
            let residuals = metrics.residuals().expect("a beam has residuals");
            let amorph::task::Metrics::Beam(beam) = &metrics else {
                panic!("a beam scene's metrics")
            };
            assert_eq!(
                residuals.len(),
                beam.profile.len() - 1,
                "every station but the clamp"
            );
            for (r, s) in residuals.iter().zip(&beam.profile[1..]) {
                assert_eq!(r[0], s[0], "at the station's position");
                assert_eq!(r[1], s[1] - s[2], "deflection less target");
            }
            // The evaluation sums the same squares in the same order.
            let sum: f64 = residuals.iter().map(|r| r[1].powi(2)).sum();
            assert_eq!(sum, -fitness, "{target}");
            evaluated += 1;
        }
    }
    assert!(
        evaluated >= 12,
        "only {evaluated} of 24 designs spanned the beam"
    );
}

#[test]
fn only_least_squares_tasks_have_residuals() {
    let robot: Scene = toml::from_str("kind = \"locomotion\"\n").expect("a locomotion scene");
    assert!(!robot.has_residuals());
    let stiffness: Scene = toml::from_str("kind = \"stiffness\"\n").expect("a stiffness scene");
    assert!(!stiffness.has_residuals());
}
