//! Crowding's replacement rule, the shared climb's nudges and the step's adaptation, on islands
//! of hand-made individuals.

use super::*;
use crate::search::fixtures::{failed, island, point_at, scored};
use crate::search::variation::LocalSearchParams;
use amorph::genome::GenomeLimits;

fn child(dominant_parent: usize, x: f64) -> Child {
    Child {
        genome: point_at(x),
        dominant_parent,
        nudge: false,
        combined: false,
    }
}

#[test]
fn a_child_replaces_its_dominant_parent_only_if_strictly_fitter() {
    let mut isl = island(0, &[0.1, 0.2, 0.3], &[-5.0, -3.0, -1.0]);
    let replaced = isl.apply(
        vec![child(0, 0.9), child(1, 0.8), child(2, 0.7)],
        vec![
            (TaskId(1), scored(-5.0)), // equal: stays
            (TaskId(2), scored(-2.0)), // fitter than -3: replaces
            (TaskId(3), scored(-4.0)), // fitter than slot 0, but slot 2 is its parent: stays
        ],
        None,
    );
    assert_eq!(replaced, 1);
    let tasks: Vec<u64> = isl.population.iter().map(|i| i.task.0).collect();
    assert_eq!(tasks, vec![0, 2, 2]);
    assert_eq!(isl.population[1].genome, point_at(0.8));
}

#[test]
fn children_meet_the_current_occupant_in_child_order() {
    // Both children descend from slot 0 (fitness -5). The first (-4) replaces it; the second
    // (-4.5) beats the original parent but not the new occupant, so it stays out.
    let mut isl = island(0, &[0.1], &[-5.0]);
    let outcomes = vec![(TaskId(1), scored(-4.0)), (TaskId(2), scored(-4.5))];
    assert_eq!(
        isl.apply(vec![child(0, 0.5), child(0, 0.6)], outcomes, None),
        1
    );
    assert_eq!(isl.population[0].task, TaskId(1));
    // In the other order both replace, one after the other.
    let mut isl = island(0, &[0.1], &[-5.0]);
    let outcomes = vec![(TaskId(2), scored(-4.5)), (TaskId(1), scored(-4.0))];
    assert_eq!(
        isl.apply(vec![child(0, 0.6), child(0, 0.5)], outcomes, None),
        2
    );
    assert_eq!(isl.population[0].task, TaskId(1));
}

#[test]
fn a_failed_child_never_replaces_and_any_evaluated_child_replaces_a_failed_parent() {
    let mut isl = island(0, &[0.1, 0.2], &[-5.0, -3.0]);
    isl.population[1].outcome = failed();
    let replaced = isl.apply(
        vec![child(0, 0.9), child(1, 0.8)],
        vec![(TaskId(1), failed()), (TaskId(2), scored(-1e9))],
        None,
    );
    assert_eq!(replaced, 1);
    assert_eq!(isl.population[0].task, TaskId(0));
    assert_eq!(isl.population[1].task, TaskId(2));
}

const DIMS: GridDims = GridDims::new(6, 20, 6);

fn breeding(local_search: LocalSearchParams) -> Breeding {
    Breeding {
        mutation: MutationParams::default(),
        local_search,
        scene: Arc::new(
            toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").expect("a beam"),
        ),
    }
}

#[test]
fn nudges_are_the_best_with_only_continuous_parameters_moved() {
    let mut isl = island(0, &[0.1, 0.2, 0.3, 0.4], &[-5.0, -1.0, -3.0, -4.0]);
    let mut best = random_genome(isl.rng_mut(), 30, &GenomeLimits::default(), 2);
    best.points[0].material = amorph::material::MaterialId(1);
    isl.population[1].genome = best.clone();
    let b = breeding(LocalSearchParams {
        fraction: 0.5,
        points: 0,
        probability: 1.0,
        step: 0.01,
        insertion: 0.0,
        ..Default::default()
    });
    let children = isl.breed(6, &b, DIMS, None);
    assert_eq!(children.iter().filter(|c| c.nudge).count(), 3);
    assert!(children[..3].iter().all(|c| !c.nudge), "nudges come last");
    for c in &children[3..] {
        assert_eq!(c.dominant_parent, 1);
        assert_eq!(c.genome.len(), best.len());
        for (p, q) in c.genome.points.iter().zip(&best.points) {
            assert_eq!(p.material, q.material);
            assert_ne!(
                p.position, q.position,
                "probability 1 moves every coordinate"
            );
        }
        c.genome
            .validate(b.scene.limits(), 2)
            .expect("within limits");
    }
}

/// Under a shared climb the nudges are of the design handed in and name its slot (in the
/// island that holds it), whatever this island's own best is; crossovers stay this island's.
#[test]
fn shared_nudges_start_from_the_run_best_not_the_island_best() {
    let mut isl = island(0, &[0.1, 0.2, 0.3], &[-1.0, -5.0, -3.0]);
    let run_best = random_genome(isl.rng_mut(), 30, &GenomeLimits::default(), 2);
    let b = breeding(LocalSearchParams {
        fraction: 0.5,
        shared: true,
        ..Default::default()
    });
    let shared = SharedBest {
        genome: run_best.clone(),
        slot: 7,
        site: None,
    };
    let children = isl.breed(4, &b, DIMS, Some(&shared));
    for c in &children[..2] {
        assert!(
            !c.nudge && c.dominant_parent < 3,
            "crossovers of this island"
        );
    }
    for c in &children[2..] {
        assert!(c.nudge);
        assert_eq!(c.dominant_parent, 7);
        assert_eq!(c.genome.len(), run_best.len());
        let moved = c
            .genome
            .points
            .iter()
            .zip(&run_best.points)
            .filter(|(p, q)| p != q)
            .count();
        assert_eq!(moved, 1, "one point of the run's best moved");
    }
}

#[test]
fn a_point_nudge_moves_exactly_the_chosen_points_and_nothing_else() {
    let mut isl = island(0, &[0.1, 0.2], &[-5.0, -1.0]);
    let best = random_genome(isl.rng_mut(), 30, &GenomeLimits::default(), 2);
    isl.population[1].genome = best.clone();
    for points in [1, 3, 40] {
        let b = breeding(LocalSearchParams {
            fraction: 1.0,
            points,
            ..Default::default()
        });
        for c in isl.breed(8, &b, DIMS, None) {
            assert!(c.nudge);
            assert_eq!(c.genome.len(), best.len());
            let moved: Vec<_> = c
                .genome
                .points
                .iter()
                .zip(&best.points)
                .filter(|(p, q)| p != q)
                .collect();
            // A Gaussian step moves all five parameters of a chosen point (a clamp to a bound
            // could leave one, never all five, where they were).
            assert_eq!(moved.len(), points.min(best.len()), "{points} points asked");
            for (p, q) in moved {
                assert_eq!(p.material, q.material);
                assert!(
                    (0..3).all(|a| p.position[a] != q.position[a])
                        || p.position.iter().any(|&v| v == 0.0 || v == 1.0)
                );
            }
            c.genome
                .validate(b.scene.limits(), 2)
                .expect("within limits");
        }
    }
}

/// Two nudges that each beat the best (moving different points) come back together as the
/// first nudge of the next epoch, judged against the island's best; a third nudge that lost
/// is not in it, and without `combine` nothing is offered.
#[test]
fn improving_nudges_return_added_up_as_the_next_epochs_first_nudge() {
    let mut isl = island(0, &[0.1, 0.2], &[-5.0, -1.0]);
    let best = random_genome(isl.rng_mut(), 4, &GenomeLimits::default(), 2);
    isl.population[1].genome = best.clone();
    let nudged = |i: usize, dx: f64| {
        let mut g = best.clone();
        g.points[i].density += dx;
        Child {
            genome: g,
            dominant_parent: 1,
            nudge: true,
            combined: false,
        }
    };
    let epoch = || {
        (
            vec![nudged(0, 0.01), nudged(1, 0.02), nudged(2, 0.03)],
            vec![
                (TaskId(1), scored(-0.8)), // beats -1: replaces the best
                (TaskId(2), scored(-0.9)), // beats -1, not -0.8: stays out, but improved
                (TaskId(3), scored(-1.5)), // worse than the best it came from
            ],
        )
    };
    let b = breeding(LocalSearchParams {
        fraction: 1.0,
        combine: true,
        ..Default::default()
    });
    let (children, outcomes) = epoch();
    assert_eq!(isl.apply(children, outcomes, Some(64)), 1);
    let next = isl.breed(3, &b, DIMS, None);
    let first = &next[0];
    assert!(first.nudge && first.combined);
    assert_eq!(first.dominant_parent, 1);
    let mut expected = best.clone();
    expected.points[0].density += 0.01;
    expected.points[1].density += 0.02;
    assert_eq!(first.genome, expected);
    assert!(next[1..].iter().all(|c| c.nudge && !c.combined));
    // The combination is offered once: the epoch after has none unless nudges improve again.
    let again = isl.breed(3, &b, DIMS, None);
    assert!(again.iter().all(|c| !c.combined));

    let mut isl = island(0, &[0.1, 0.2], &[-5.0, -1.0]);
    isl.population[1].genome = best.clone();
    let (children, outcomes) = epoch();
    isl.apply(children, outcomes, None);
    assert!(isl.breed(3, &b, DIMS, None).iter().all(|c| !c.combined));
}
