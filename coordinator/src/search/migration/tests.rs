use super::*;
use crate::search::fixtures::{island, point_at};
use rand::SeedableRng;

fn rng() -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(7)
}

fn params(topology: Topology, replacement: ArrivalReplacement) -> MigrationParams {
    MigrationParams {
        interval: 1,
        count: 1,
        topology,
        selection: EmigrantSelection::Best,
        replacement,
        only_if_fitter: true,
    }
}

#[test]
fn a_ring_is_one_way_and_closes_on_itself() {
    let l = links(Topology::Ring, 4, &mut rng());
    assert_eq!(l, vec![(0, 1), (1, 2), (2, 3), (3, 0)]);
    for &(a, b) in &l {
        assert!(!l.contains(&(b, a)), "{a} -> {b} is sent back");
    }
    assert!(links(Topology::Ring, 1, &mut rng()).is_empty());
}

#[test]
fn fully_connected_links_every_ordered_pair_once() {
    let l = links(Topology::FullyConnected, 4, &mut rng());
    assert_eq!(l.len(), 12);
    assert!(l.iter().all(|&(a, b)| a != b));
    let mut unique = l.clone();
    unique.dedup();
    assert_eq!(unique, l);
}

#[test]
fn random_links_at_probability_zero_and_one_are_none_and_all() {
    assert!(links(Topology::Random { probability: 0.0 }, 5, &mut rng()).is_empty());
    assert_eq!(
        links(Topology::Random { probability: 1.0 }, 5, &mut rng()),
        links(Topology::FullyConnected, 5, &mut rng())
    );
}

#[test]
fn the_best_leaves_from_the_snapshot_and_replaces_the_worst() {
    let mut islands = vec![
        island(0, &[0.1, 0.2, 0.3], &[-1.0, -9.0, -4.0]),
        island(1, &[0.6, 0.7, 0.8], &[-5.0, -6.0, -2.0]),
    ];
    let p = params(Topology::Ring, ArrivalReplacement::Worst);
    let events = migrate(&mut islands, &p, &mut rng());
    // 0 -> 1: island 0's best (slot 0) replaces island 1's worst (slot 1).
    assert_eq!((events[0].emigrant, events[0].replaced), (0, Some(1)));
    assert_eq!(islands[1].population[1].task, TaskId(0));
    // 1 -> 0: island 1's best *before* anyone arrived (slot 2, not the newcomer) replaces
    // island 0's worst (slot 1).
    assert_eq!((events[1].emigrant, events[1].replaced), (2, Some(1)));
    assert_eq!(islands[0].population[1].task, TaskId(102));
}

#[test]
fn a_migrant_replaces_only_if_fitter() {
    let mut islands = vec![
        island(0, &[0.1, 0.2], &[-10.0, -10.0]),
        island(1, &[0.6, 0.7], &[-1.0, -2.0]),
    ];
    let before = islands[1].population.clone();
    let p = params(Topology::Ring, ArrivalReplacement::Worst);
    let events = migrate(&mut islands, &p, &mut rng());
    assert_eq!(
        events[0].replaced, None,
        "a less fit migrant is turned away"
    );
    assert_eq!(islands[1].population, before);
    // Equal fitness is not fitter either.
    let mut islands = vec![island(0, &[0.1], &[-3.0]), island(1, &[0.9], &[-3.0])];
    let events = migrate(&mut islands, &p, &mut rng());
    assert!(events.iter().all(|e| e.replaced.is_none()));
}

#[test]
fn without_only_if_fitter_a_migrant_always_takes_its_place() {
    let mut islands = vec![
        island(0, &[0.1, 0.2], &[-10.0, -10.0]),
        island(1, &[0.6, 0.7], &[-1.0, -2.0]),
    ];
    let p = MigrationParams {
        only_if_fitter: false,
        ..params(Topology::Ring, ArrivalReplacement::Worst)
    };
    let events = migrate(&mut islands, &p, &mut rng());
    assert_eq!(events[0].replaced, Some(1));
    assert_eq!(islands[1].population[1].task, TaskId(0));
}

#[test]
fn most_similar_replaces_the_resident_nearest_by_genome_distance() {
    // The migrant sits at x = 0.45; residents at 0.1, 0.5, 0.9 are 0.35, 0.05, 0.45 away.
    let mut islands = vec![
        island(0, &[0.45], &[-1.0]),
        island(1, &[0.1, 0.5, 0.9], &[-10.0, -10.0, -20.0]),
    ];
    let p = MigrationParams {
        topology: Topology::FullyConnected,
        ..params(Topology::Ring, ArrivalReplacement::MostSimilar)
    };
    let events = migrate(&mut islands, &p, &mut rng());
    let to_1 = events.iter().find(|e| e.to == IslandId(1)).unwrap();
    assert_eq!(
        to_1.replaced,
        Some(1),
        "not the worst (slot 2) but the nearest"
    );
    assert_eq!(islands[1].population[1].genome, point_at(0.45));
}

#[test]
fn genome_distance_is_symmetric_zero_on_itself_and_the_point_gap() {
    let a = point_at(0.2);
    let b = point_at(0.7);
    assert_eq!(genome_distance(&a, &a), 0.0);
    assert_eq!(genome_distance(&a, &b), genome_distance(&b, &a));
    assert!((genome_distance(&a, &b) - 0.5).abs() < 1e-15);
}
