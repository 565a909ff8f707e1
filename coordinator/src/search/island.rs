//! One island: a deterministic-crowding population (paper §II-C) bred in epochs.
//!
//! An epoch breeds all its children from one snapshot of the population, so they can be evaluated
//! in parallel; replacements are then applied in child order against the parents' *current*
//! fitness. The result depends only on the island's RNG stream, never on who evaluated what when.

use amorph::genome::{
    CutPlane, DominantParent, Genome, GenomeLimits, MutationParams, crossover, mutate,
    random_genome,
};
use amorph::task::Outcome;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use crate::ids::{IslandId, TaskId};

/// A member of a population and how it scored.
#[derive(Clone, Debug, PartialEq)]
pub struct Individual {
    pub genome: Genome,
    pub outcome: Outcome,
    /// The task whose evaluation gave `outcome` (its row in the run store).
    pub task: TaskId,
}

/// A child waiting for evaluation, with the population slot of its dominant parent.
#[derive(Clone, Debug, PartialEq)]
pub struct Child {
    pub genome: Genome,
    pub dominant_parent: usize,
    pub parents: [usize; 2],
}

/// How an island breeds (shared by all islands of a run).
#[derive(Clone, Debug, PartialEq)]
pub struct Breeding {
    pub mutation: MutationParams,
    pub limits: GenomeLimits,
    pub material_count: usize,
}

#[derive(Debug)]
pub struct Island {
    pub id: IslandId,
    pub population: Vec<Individual>,
    rng: ChaCha8Rng,
}

impl Island {
    /// Draws the initial genomes of an island from its RNG stream; they still need evaluating
    /// (see [`Island::from_evaluated`]).
    pub fn initial_genomes(
        rng: &mut ChaCha8Rng,
        size: usize,
        points: usize,
        breeding: &Breeding,
    ) -> Vec<Genome> {
        (0..size)
            .map(|_| random_genome(rng, points, &breeding.limits, breeding.material_count))
            .collect()
    }

    pub fn from_evaluated(id: IslandId, rng: ChaCha8Rng, population: Vec<Individual>) -> Self {
        Self {
            id,
            population,
            rng,
        }
    }

    /// Breeds `count` children from the current snapshot: two distinct random parents, a random
    /// cut plane, the dominant parent, then mutation.
    pub fn breed(&mut self, count: usize, breeding: &Breeding) -> Vec<Child> {
        let n = self.population.len();
        (0..count)
            .map(|_| {
                let a = self.rng.random_range(0..n);
                let b = if n > 1 {
                    let b = self.rng.random_range(0..n - 1);
                    if b >= a { b + 1 } else { b }
                } else {
                    a
                };
                let plane = CutPlane::random(&mut self.rng);
                let cross = crossover(
                    &self.population[a].genome,
                    &self.population[b].genome,
                    &plane,
                    breeding.limits.max_points,
                );
                let mut genome = cross.child;
                mutate(
                    &mut genome,
                    &mut self.rng,
                    &breeding.mutation,
                    &breeding.limits,
                    breeding.material_count,
                );
                let dominant_parent = match cross.dominant {
                    DominantParent::A => a,
                    DominantParent::B => b,
                };
                Child {
                    genome,
                    dominant_parent,
                    parents: [a, b],
                }
            })
            .collect()
    }

    /// Applies an epoch's evaluated children in order: each replaces its dominant parent only if
    /// strictly fitter than that slot's current occupant. Returns how many replaced.
    pub fn apply(&mut self, children: Vec<Child>, outcomes: Vec<(TaskId, Outcome)>) -> usize {
        assert_eq!(children.len(), outcomes.len(), "one outcome per child");
        let mut replaced = 0;
        for (child, (task, outcome)) in children.into_iter().zip(outcomes) {
            let slot = &mut self.population[child.dominant_parent];
            if outcome.is_fitter_than(&slot.outcome) {
                *slot = Individual {
                    genome: child.genome,
                    outcome,
                    task,
                };
                replaced += 1;
            }
        }
        replaced
    }

    /// Index of the fittest individual (the lowest index on a tie).
    pub fn best_index(&self) -> usize {
        let mut best = 0;
        for (i, ind) in self.population.iter().enumerate() {
            if ind.outcome.is_fitter_than(&self.population[best].outcome) {
                best = i;
            }
        }
        best
    }

    pub fn best(&self) -> &Individual {
        &self.population[self.best_index()]
    }

    /// Index of the least fit individual (the lowest index on a tie).
    pub fn worst_index(&self) -> usize {
        let mut worst = 0;
        for (i, ind) in self.population.iter().enumerate() {
            if self.population[worst].outcome.is_fitter_than(&ind.outcome) {
                worst = i;
            }
        }
        worst
    }

    pub fn rng_mut(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }
}
