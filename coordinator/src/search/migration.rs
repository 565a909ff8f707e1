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
            let admitted = !params.only_if_fitter || dest.admits(&migrant.outcome, target);
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
mod tests;
