//! One island: a deterministic-crowding population (paper §II-C) bred in epochs.
//!
//! An epoch breeds all its children from one snapshot of the population, so they can be evaluated
//! in parallel; replacements are then applied in child order against the parents' *current*
//! fitness. The result depends only on the island's RNG stream, never on who evaluated what when.

use amorph::genome::{
    CutPlane, DominantParent, Genome, MutationParams, crossover, mutate, random_genome,
};
use std::sync::Arc;
use tracing::info;

use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::combination::combine;
use super::insertion::BoundarySite;
use super::objectives::{Pareto, Selection};
use super::variation::LocalSearchParams;
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
    /// A nudge of the island's best (local search) rather than a crossover child.
    pub nudge: bool,
    /// The last epoch's improving nudges applied together (`local_search.combine`): judged by
    /// this island against its best, never handed to another island, never itself combined.
    pub combined: bool,
}

/// The design every island's nudges start from under `local_search.shared`: the run's best, its
/// slot in the island that holds it, and its boundary for insertions (at the current resolution).
#[derive(Debug)]
pub struct SharedBest {
    pub genome: Genome,
    pub slot: usize,
    pub site: Option<BoundarySite>,
}

/// How an island breeds (shared by all islands of a run).
#[derive(Clone, Debug, PartialEq)]
pub struct Breeding {
    pub mutation: MutationParams,
    /// The local climb around the best (off in the paper's search).
    pub local_search: LocalSearchParams,
    /// The task: its genome limits and palette bound every operator, and boundary insertion
    /// looks at the design a genome makes.
    pub scene: Arc<Scene>,
}

#[derive(Clone, Debug)]
pub struct Island {
    pub id: IslandId,
    pub population: Vec<Individual>,
    rng: ChaCha8Rng,
    /// The last epoch's improving nudges applied together, offered as the first nudge of the next.
    combination: Option<Genome>,
    /// A multi-objective run's objectives: members then stand by Pareto front and crowding
    /// instead of by fitness.
    pareto: Option<Pareto>,
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
            .map(|_| {
                random_genome(
                    rng,
                    points,
                    breeding.scene.limits(),
                    breeding.scene.palette().len(),
                )
            })
            .collect()
    }

    pub fn from_evaluated(id: IslandId, rng: ChaCha8Rng, population: Vec<Individual>) -> Self {
        Self {
            id,
            population,
            rng,
            combination: None,
            pareto: None,
        }
    }

    /// Makes the island keep its population by `pareto`'s objectives (a multi-objective run).
    pub fn with_pareto(mut self, pareto: Option<Pareto>) -> Self {
        self.pareto = pareto;
        self
    }

    /// The resolution the population is now evaluated at (after a switch).
    pub fn at_resolution(&mut self, dims: GridDims) {
        if let Some(pareto) = &mut self.pareto {
            pareto.dims = dims;
        }
    }

    fn outcomes(&self) -> Vec<&Outcome> {
        self.population.iter().map(|i| &i.outcome).collect()
    }

    /// Breeds `count` children from the current snapshot: two distinct random parents, a cut
    /// plane, the dominant parent, then mutation; the last few are nudges of the best when a local
    /// search is configured (some of them point insertions on the best's design at `dims`, the
    /// run's current resolution). With `shared` (the run's best: its genome, its slot in the
    /// island holding it, and its boundary), the nudges are of that design and name its slot as
    /// their dominant parent; the caller hands them to the island that holds it.
    pub fn breed(
        &mut self,
        count: usize,
        breeding: &Breeding,
        dims: GridDims,
        shared: Option<&SharedBest>,
    ) -> Vec<Child> {
        let local = &breeding.local_search;
        let nudges = local.nudges(count);
        let mut children: Vec<Child> = (0..count - nudges)
            .map(|_| self.crossover_child(breeding))
            .collect();
        let own;
        let from = match shared {
            Some(shared) => shared,
            None => {
                let slot = self.best_index();
                let genome = self.population[slot].genome.clone();
                let site = (nudges > 0)
                    .then(|| local.boundary_site(&genome, &breeding.scene, dims))
                    .flatten();
                own = SharedBest { genome, slot, site };
                &own
            }
        };
        // The combination judges against this island's own best, whatever `shared` says: the
        // nudges it adds up were judged here, so this island holds their lineage.
        let combined = self.combination.take().filter(|_| nudges > 0);
        let offered = usize::from(combined.is_some());
        if let Some(genome) = combined {
            children.push(Child {
                genome,
                dominant_parent: self.best_index(),
                nudge: true,
                combined: true,
            });
        }
        for _ in offered..nudges {
            let mut genome = from.genome.clone();
            local.step_from_best(
                &mut genome,
                &mut self.rng,
                from.site.as_ref(),
                &breeding.scene,
            );
            children.push(Child {
                genome,
                dominant_parent: from.slot,
                nudge: true,
                combined: false,
            });
        }
        children
    }

    fn crossover_child(&mut self, breeding: &Breeding) -> Child {
        let n = self.population.len();
        let (a, b) = match &self.pareto {
            Some(pareto) if pareto.selection == Selection::Nsga2 => {
                // Binary tournaments on standing (the lower slot on a tie), as NSGA-II breeds.
                let standings = pareto.standings(&self.outcomes());
                let mut tournament = || {
                    let (x, y) = (self.rng.random_range(0..n), self.rng.random_range(0..n));
                    let better = super::objectives::stands_better(standings[y], standings[x]);
                    if better || (standings[y] == standings[x] && y < x) {
                        y
                    } else {
                        x
                    }
                };
                (tournament(), tournament())
            }
            _ => {
                let a = self.rng.random_range(0..n);
                let b = if n > 1 {
                    let b = self.rng.random_range(0..n - 1);
                    if b >= a { b + 1 } else { b }
                } else {
                    a
                };
                (a, b)
            }
        };
        let plane = CutPlane::random(&mut self.rng);
        let cross = crossover(
            &self.population[a].genome,
            &self.population[b].genome,
            &plane,
            breeding.scene.limits().max_points,
        );
        let mut genome = cross.child;
        mutate(
            &mut genome,
            &mut self.rng,
            &breeding.mutation,
            breeding.scene.limits(),
            breeding.scene.palette().len(),
        );
        let dominant_parent = match cross.dominant {
            DominantParent::A => a,
            DominantParent::B => b,
        };
        Child {
            genome,
            dominant_parent,
            nudge: false,
            combined: false,
        }
    }

    /// Which of an epoch's evaluated children would replace their dominant parent, in order: each
    /// only if strictly fitter than that slot's occupant at its turn (an earlier child of the
    /// epoch may have taken it).
    ///
    /// In a multi-objective run: by the Pareto crowding rule ([`Pareto::replaces`]), or under
    /// NSGA-II whether the child survives the cut of the population and the epoch's children.
    pub fn winners<'a>(&'a self, children: &[Child], outcomes: &[&'a Outcome]) -> Vec<bool> {
        let mut slots: Vec<&Outcome> = self.outcomes();
        if let Some(pareto) = self.pareto.as_ref()
            && pareto.selection == Selection::Nsga2
        {
            let n = slots.len();
            slots.extend(outcomes);
            let survivors = pareto.survivors(&slots, n);
            return (n..n + children.len())
                .map(|k| survivors.binary_search(&k).is_ok())
                .collect();
        }
        children
            .iter()
            .zip(outcomes)
            .map(|(child, &outcome)| {
                let slot = child.dominant_parent;
                let wins = match &self.pareto {
                    Some(pareto) => pareto.replaces(&slots, slot, outcome),
                    None => outcome.is_fitter_than(slots[slot]),
                };
                if wins {
                    slots[slot] = outcome;
                }
                wins
            })
            .collect()
    }

    /// Whether `newcomer` (a migrant) would take slot `slot`: fitter than its occupant, or in a
    /// multi-objective run by the Pareto crowding rule.
    pub fn admits(&self, newcomer: &Outcome, slot: usize) -> bool {
        match &self.pareto {
            Some(pareto) => pareto.replaces(&self.outcomes(), slot, newcomer),
            None => newcomer.is_fitter_than(&self.population[slot].outcome),
        }
    }

    /// Applies an epoch's evaluated children in order ([`Island::winners`]). Returns how many
    /// replaced their dominant parent. With `combine` (`local_search.combine`, the genome's point
    /// limit), also adds up the epoch's improving nudges for the next epoch.
    pub fn apply(
        &mut self,
        children: Vec<Child>,
        outcomes: Vec<(TaskId, Outcome)>,
        combine: Option<usize>,
    ) -> usize {
        assert_eq!(children.len(), outcomes.len(), "one outcome per child");
        let refs: Vec<&Outcome> = outcomes.iter().map(|(_, o)| o).collect();
        let wins = self.winners(&children, &refs);
        if self
            .pareto
            .as_ref()
            .is_some_and(|p| p.selection == Selection::Nsga2)
        {
            return self.cut(children, outcomes, &wins);
        }
        self.combination =
            combine.and_then(|max_points| self.combine_improving(&children, &refs, max_points));
        let mut replaced = 0;
        for ((child, (task, outcome)), wins) in children.into_iter().zip(outcomes).zip(wins) {
            if child.combined {
                info!(island = %self.id, won = wins, "combined nudges judged");
            }
            if wins {
                self.population[child.dominant_parent] = Individual {
                    genome: child.genome,
                    outcome,
                    task,
                };
                replaced += 1;
            }
        }
        replaced
    }

    /// NSGA-II's replacement: the population becomes the survivors of itself and its children,
    /// in that order ([`Pareto::survivors`]); `wins` says which children survived.
    fn cut(
        &mut self,
        children: Vec<Child>,
        outcomes: Vec<(TaskId, Outcome)>,
        wins: &[bool],
    ) -> usize {
        let n = self.population.len();
        let mut merged: Vec<Individual> = std::mem::take(&mut self.population);
        merged.extend(
            children
                .into_iter()
                .zip(outcomes)
                .map(|(child, (task, outcome))| Individual {
                    genome: child.genome,
                    outcome,
                    task,
                }),
        );
        let refs: Vec<&Outcome> = merged.iter().map(|i| &i.outcome).collect();
        let survivors = self.pareto.as_ref().expect("NSGA-II").survivors(&refs, n);
        let mut survivors = survivors.into_iter().peekable();
        self.population = (merged.into_iter().enumerate())
            .filter(|(k, _)| survivors.next_if_eq(k).is_some())
            .map(|(_, individual)| individual)
            .collect();
        wins.iter().filter(|&&w| w).count()
    }

    /// The nudges of this epoch that beat the design they started from (the snapshot occupant of
    /// their dominant parent's slot, before any child of the epoch is applied), fittest first
    /// (child order on a tie), added up by [`combine`].
    fn combine_improving(
        &self,
        children: &[Child],
        outcomes: &[&Outcome],
        max_points: usize,
    ) -> Option<Genome> {
        let mut improving: Vec<(usize, &Child)> = (children.iter().enumerate())
            .filter(|(k, c)| {
                c.nudge
                    && !c.combined
                    && outcomes[*k].is_fitter_than(&self.population[c.dominant_parent].outcome)
            })
            .collect();
        // Nudges of one epoch share one base (the island's best, or the run's under `shared`).
        let slot = improving.first().map(|(_, c)| c.dominant_parent)?;
        improving.retain(|(_, c)| c.dominant_parent == slot);
        // A stable sort, so ties keep child order.
        improving.sort_by(|(a, _), (b, _)| outcomes[*b].rank().total_cmp(&outcomes[*a].rank()));
        let genomes: Vec<&Genome> = improving.iter().map(|(_, c)| &c.genome).collect();
        let combined = combine(&self.population[slot].genome, &genomes, max_points);
        if combined.is_some() {
            info!(island = %self.id, improving = genomes.len(), "improving nudges combined");
        }
        combined
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

    /// The hypervolume of a multi-objective island's population (`None` in a single-objective
    /// run).
    pub fn hypervolume(&self) -> Option<f64> {
        Some(self.pareto.as_ref()?.hypervolume(&self.outcomes()))
    }

    /// The objectives' definitions and this population's values, if a multi-objective run.
    pub fn pareto(&self) -> Option<&Pareto> {
        self.pareto.as_ref()
    }

    /// Slots from the fittest to the least fit (the lower slot first on a tie); in a
    /// multi-objective run from the best standing to the worst.
    pub fn ranked_slots(&self) -> Vec<usize> {
        if let Some(pareto) = &self.pareto {
            return pareto.ranked(&self.outcomes());
        }
        let pop = &self.population;
        let mut order: Vec<usize> = (0..pop.len()).collect();
        order.sort_by(|&a, &b| {
            (pop[b].outcome.rank())
                .total_cmp(&pop[a].outcome.rank())
                .then(a.cmp(&b))
        });
        order
    }

    /// Index of the least fit individual (the lowest index on a tie); in a multi-objective run,
    /// of the worst standing.
    pub fn worst_index(&self) -> usize {
        if self.pareto.is_some() {
            return *self.ranked_slots().last().expect("a population");
        }
        let mut worst = 0;
        for (i, ind) in self.population.iter().enumerate() {
            if self.population[worst].outcome.is_fitter_than(&ind.outcome) {
                worst = i;
            }
        }
        worst
    }

    #[cfg(test)]
    pub fn rng_mut(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }
}

#[cfg(test)]
mod tests;
