//! The local climb's keys: validation, how many of an epoch's children are nudges, and what a
//! nudge does to the best design.

use super::*;
use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::task::Scene;
use rand::SeedableRng;

#[test]
fn nudges_round_to_the_nearest_child() {
    let l = LocalSearchParams {
        fraction: 0.2,
        ..Default::default()
    };
    assert_eq!(l.nudges(50), 10);
    assert_eq!(l.nudges(3), 1);
    assert_eq!(LocalSearchParams::default().nudges(50), 0);
}

#[test]
fn the_finest_fraction_acts_only_at_the_finest_level() {
    let l = LocalSearchParams {
        fraction: 0.5,
        finest_fraction: Some(1.0),
        ..Default::default()
    };
    assert_eq!(l.at_level(false).nudges(48), 24);
    assert_eq!(l.at_level(true).nudges(48), 48);
    let unset = LocalSearchParams {
        fraction: 0.5,
        ..Default::default()
    };
    assert_eq!(
        unset.at_level(true),
        unset,
        "unset, the finest level breeds as the others"
    );
}

#[test]
fn each_bad_field_is_named() {
    assert!(LocalSearchParams::default().validate().is_ok());
    let bad = |edit: fn(&mut LocalSearchParams)| {
        let mut l = LocalSearchParams::default();
        edit(&mut l);
        l.validate().unwrap_err()
    };
    assert!(bad(|l| l.fraction = f64::NAN).contains("search.local_search.fraction"));
    assert!(bad(|l| l.finest_fraction = Some(1.5)).contains("search.local_search.finest_fraction"));
    assert!(bad(|l| l.probability = -0.1).contains("search.local_search.probability"));
    assert!(bad(|l| l.insertion = 2.0).contains("search.local_search.insertion"));
    assert!(bad(|l| l.step = 0.0).contains("search.local_search.step"));
    assert!(bad(|l| l.step = f64::INFINITY).contains("search.local_search.step"));
}

fn point(x: f64, y: f64) -> GaussianPoint {
    GaussianPoint {
        position: [x, y, 0.5],
        density: 0.0,
        falloff: 0.2,
        material: MaterialId((x * 10.0) as u8 % 2),
    }
}

/// A nudge moves the continuous parameters of at most `points` of the best's points, never a
/// material or the point count, and each moved parameter by a Gaussian step whose standard
/// deviation is `step` times the parameter's range. Every point sits far enough from the edges
/// that clamping (six standard deviations away) cannot shorten a step.
#[test]
fn a_nudge_moves_at_most_points_points_by_a_gaussian_step() {
    let scene: Scene = toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").unwrap();
    let best = Genome {
        points: (0..10)
            .map(|i| point(0.3 + 0.04 * i as f64, 0.6 - 0.02 * i as f64))
            .collect(),
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for points in [1, 3] {
        let l = LocalSearchParams {
            points,
            step: 0.02,
            ..Default::default()
        };
        let mut moves = Vec::new();
        for _ in 0..2000 {
            let mut child = best.clone();
            l.step_from_best(&mut child, &mut rng, None, &scene);
            assert_eq!(child.points.len(), best.points.len(), "no point added");
            let moved: Vec<usize> = (0..best.points.len())
                .filter(|&i| child.points[i] != best.points[i])
                .collect();
            assert!(moved.len() <= points, "{} points moved", moved.len());
            for i in moved {
                let (a, b) = (&best.points[i], &child.points[i]);
                assert_eq!(a.material, b.material, "a nudge keeps materials");
                // Positions span [0, 1]: the move is the step in range units.
                moves.extend((0..3).map(|k| b.position[k] - a.position[k]));
            }
        }
        let n = moves.len() as f64;
        let sd = (moves.iter().map(|d| d * d).sum::<f64>() / n).sqrt();
        // The sample standard deviation of n Gaussian draws has a relative standard error of
        // 1/sqrt(2n) (under 0.7 % here); five of them bound a correct draw's estimate.
        let tolerance = 5.0 / (2.0 * n).sqrt();
        assert!(
            (sd / l.step - 1.0).abs() < tolerance,
            "{points} points: sd {sd} for a step of {}",
            l.step
        );
    }
}
