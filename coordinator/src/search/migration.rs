//! Migration between islands: every few epochs, copies of some individuals leave each island for
//! its neighbours in a topology and take the place of residents there.

use amorph::genome::Genome;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::island::{Individual, Island};
use crate::ids::{IslandId, TaskId};

/// Which islands send migrants to which.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Topology {
    /// Island i sends to island i + 1 (the last to the first).
    Ring,
    /// Every island sends to every other.
    FullyConnected,
    /// Each ordered pair of islands is linked with this probability at every migration.
    Random { probability: f64 },
}

/// Who leaves an island.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EmigrantSelection {
    /// The fittest individuals.
    Best,
    /// Individuals drawn at random (without replacement).
    Random,
}

/// Whom an arriving migrant replaces; by default it replaces only if strictly fitter, so migration
/// never lowers an island's fitness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ArrivalReplacement {
    /// The least fit resident.
    Worst,
    /// The resident whose genome is closest to the migrant's (keeps niches apart, in the spirit of
    /// crowding).
    MostSimilar,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MigrationParams {
    /// Epochs between migrations; 0 disables migration.
    pub interval: usize,
    /// Emigrants each island sends along each link.
    pub count: usize,
    pub topology: Topology,
    pub selection: EmigrantSelection,
    pub replacement: ArrivalReplacement,
    /// A migrant takes its place only if strictly fitter than the resident (true, the default);
    /// false lets it in regardless, which with `most_similar` moves a niche's occupant instead of
    /// spreading the best everywhere.
    pub only_if_fitter: bool,
}

impl Default for MigrationParams {
    fn default() -> Self {
        Self {
            interval: 10,
            count: 1,
            topology: Topology::Ring,
            selection: EmigrantSelection::Best,
            replacement: ArrivalReplacement::Worst,
            only_if_fitter: true,
        }
    }
}

/// One migrant's journey, for the log and the run store.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MigrationEvent {
    pub from: IslandId,
    pub to: IslandId,
    /// Slot of the emigrant in its home island.
    pub emigrant: usize,
    /// Slot it took in the destination, if it was fit enough to take one.
    pub replaced: Option<usize>,
    /// The task that evaluated the migrant (its genome's row in the run store).
    pub task: TaskId,
}

/// A symmetric, cheap genome distance: the mean distance from each point to the nearest point of
/// the other genome, both ways (Chamfer distance on positions).
pub fn genome_distance(a: &Genome, b: &Genome) -> f64 {
    let one_way = |a: &Genome, b: &Genome| {
        if a.points.is_empty() {
            return 0.0;
        }
        let total: f64 = a
            .points
            .iter()
            .map(|p| {
                b.points
                    .iter()
                    .map(|q| {
                        (0..3)
                            .map(|i| (p.position[i] - q.position[i]).powi(2))
                            .sum::<f64>()
                    })
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .sum();
        total / a.points.len() as f64
    };
    if a.points.is_empty() || b.points.is_empty() {
        return if a.points.len() == b.points.len() {
            0.0
        } else {
            f64::INFINITY
        };
    }
    0.5 * (one_way(a, b) + one_way(b, a))
}

/// The directed links of a topology for `n` islands at this migration.
fn links(topology: Topology, n: usize, rng: &mut ChaCha8Rng) -> Vec<(usize, usize)> {
    match topology {
        Topology::Ring if n > 1 => (0..n).map(|i| (i, (i + 1) % n)).collect(),
        Topology::Ring => Vec::new(),
        Topology::FullyConnected => (0..n)
            .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
            .collect(),
        Topology::Random { probability } => {
            let mut out = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    if i != j && rng.random_bool(probability) {
                        out.push((i, j));
                    }
                }
            }
            out
        }
    }
}

/// Migrates between islands. Emigrants are chosen from a snapshot taken before anyone arrives, so
/// the result does not depend on the order links are processed in beyond that fixed order.
pub fn migrate(
    islands: &mut [Island],
    params: &MigrationParams,
    rng: &mut ChaCha8Rng,
) -> Vec<MigrationEvent> {
    let n = islands.len();
    if params.count == 0 || n < 2 {
        return Vec::new();
    }
    let links = links(params.topology, n, rng);
    // Choose emigrants per link from the pre-migration snapshot.
    let mut departures: Vec<(usize, usize, usize, Individual)> = Vec::new();
    for &(from, to) in &links {
        let island = &islands[from];
        let mut order: Vec<usize> = (0..island.population.len()).collect();
        match params.selection {
            EmigrantSelection::Best => order = island.ranked_slots(),
            EmigrantSelection::Random => {
                for i in (1..order.len()).rev() {
                    let j = rng.random_range(0..=i);
                    order.swap(i, j);
                }
            }
        }
        for &slot in order.iter().take(params.count) {
            departures.push((from, to, slot, island.population[slot].clone()));
        }
    }
    departures
        .into_iter()
        .map(|(from, to, emigrant, migrant)| {
            let task = migrant.task;
            let dest = &mut islands[to];
            let target = match params.replacement {
                ArrivalReplacement::Worst => dest.worst_index(),
                ArrivalReplacement::MostSimilar => (0..dest.population.len())
                    .min_by(|&a, &b| {
                        genome_distance(&migrant.genome, &dest.population[a].genome)
                            .total_cmp(&genome_distance(
                                &migrant.genome,
                                &dest.population[b].genome,
                            ))
                            .then(a.cmp(&b))
                    })
                    .unwrap_or(0),
            };
            let admitted = !params.only_if_fitter
                || migrant
                    .outcome
                    .is_fitter_than(&dest.population[target].outcome);
            let replaced = admitted.then(|| {
                dest.population[target] = migrant;
                target
            });
            MigrationEvent {
                from: islands_id(from),
                to: islands_id(to),
                emigrant,
                replaced,
                task,
            }
        })
        .collect()
}

fn islands_id(i: usize) -> IslandId {
    IslandId(i as u32)
}

#[cfg(test)]
mod tests {
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
}
