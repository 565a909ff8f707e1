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
use super::variation::Variation;
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
    /// Policies beyond the paper's operators (all off by default).
    pub variation: Variation,
    /// The task: its genome limits and palette bound every operator, and boundary insertion
    /// looks at the design a genome makes.
    pub scene: Arc<Scene>,
}

#[derive(Clone, Debug)]
pub struct Island {
    pub id: IslandId,
    pub population: Vec<Individual>,
    rng: ChaCha8Rng,
    /// The mutation step of the next epoch as a multiple of `search.mutation.step` (1 unless the
    /// step adapts).
    step_scale: f64,
    /// Crossover children of the last epoch that replaced their dominant parent, and how many
    /// there were: the evidence the step adapts to.
    last_success: (usize, usize),
    /// The last epoch's improving nudges applied together, offered as the first nudge of the next.
    combination: Option<Genome>,
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
            step_scale: 1.0,
            last_success: (0, 0),
            combination: None,
        }
    }

    /// The mutation step of the coming epoch as a multiple of the configured one.
    pub fn step_scale(&self) -> f64 {
        self.step_scale
    }

    /// Breeds `count` children from the current snapshot: two distinct random parents, a cut
    /// plane, the dominant parent, then mutation; the last few are nudges of the best when a local
    /// search is configured (some of them point insertions on the best's design at `dims`, the
    /// run's current resolution). The mutation step first adapts to the last epoch's success.
    /// With `shared` (the run's best: its genome, its slot in the island holding it, and its
    /// boundary), the nudges are of that design and name its slot as their dominant parent; the
    /// caller hands them to the island that holds it.
    pub fn breed(
        &mut self,
        count: usize,
        breeding: &Breeding,
        dims: GridDims,
        shared: Option<&SharedBest>,
    ) -> Vec<Child> {
        let (replaced, tried) = self.last_success;
        self.step_scale =
            breeding
                .variation
                .step_adaptation
                .next_scale(self.step_scale, replaced, tried);
        self.last_success = (0, 0);
        let mutation = MutationParams {
            step: breeding.mutation.step * self.step_scale,
            ..breeding.mutation.clone()
        };
        let nudges = breeding.variation.local_search.nudges(count);
        let mut children: Vec<Child> = (0..count - nudges)
            .map(|_| self.crossover_child(breeding, &mutation))
            .collect();
        let local = &breeding.variation.local_search;
        let own;
        let from = match shared {
            Some(shared) => shared,
            None => {
                let slot = self.best_index();
                let genome = self.population[slot].genome.clone();
                let site = (nudges > 0 && local.insertion > 0.0)
                    .then(|| BoundarySite::new(&genome, &breeding.scene, dims));
                own = SharedBest { genome, slot, site };
                &own
            }
        };
        // The combination judges against this island's own best, whatever `shared` says: the
        // nudges it adds up were judged here, so this island holds their lineage.
        let combination = self.combination.take().filter(|_| nudges > 0);
        let offered = usize::from(combination.is_some());
        if let Some(genome) = combination {
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

    fn crossover_child(&mut self, breeding: &Breeding, mutation: &MutationParams) -> Child {
        let n = self.population.len();
        let a = self.rng.random_range(0..n);
        let b = if n > 1 {
            let b = self.rng.random_range(0..n - 1);
            if b >= a { b + 1 } else { b }
        } else {
            a
        };
        let across = &breeding.variation.crossover;
        // The draw is skipped when the option is off, so the paper's search keeps its RNG stream.
        let plane =
            if across.across_probability > 0.0 && self.rng.random_bool(across.across_probability) {
                CutPlane::across(&mut self.rng, across.axis)
            } else {
                CutPlane::random(&mut self.rng)
            };
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
            mutation,
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
    pub fn winners<'a>(&'a self, children: &[Child], outcomes: &[&'a Outcome]) -> Vec<bool> {
        let mut slots: Vec<&Outcome> = self.population.iter().map(|i| &i.outcome).collect();
        children
            .iter()
            .zip(outcomes)
            .map(|(child, &outcome)| {
                let slot = &mut slots[child.dominant_parent];
                let wins = outcome.is_fitter_than(slot);
                if wins {
                    *slot = outcome;
                }
                wins
            })
            .collect()
    }

    /// Applies an epoch's evaluated children in order ([`Island::winners`]). Returns how many
    /// replaced their dominant parent. With `combine` (`local_search.combine`), first adds up the
    /// nudges that beat the design they were nudged from, for the next epoch.
    pub fn apply(
        &mut self,
        children: Vec<Child>,
        outcomes: Vec<(TaskId, Outcome)>,
        combine: Option<usize>,
    ) -> usize {
        assert_eq!(children.len(), outcomes.len(), "one outcome per child");
        let refs: Vec<&Outcome> = outcomes.iter().map(|(_, o)| o).collect();
        let wins = self.winners(&children, &refs);
        self.combination = combine
            .and_then(|max_points| self.combine_improving_nudges(&children, &refs, max_points));
        let mut replaced = 0;
        for ((child, (task, outcome)), wins) in children.into_iter().zip(outcomes).zip(wins) {
            if child.combined {
                info!(island = %self.id, won = wins, "combined nudges judged");
            }
            if !child.nudge {
                self.last_success.1 += 1;
                self.last_success.0 += usize::from(wins);
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

    /// The nudges of this epoch that beat the design they started from (the snapshot occupant of
    /// their dominant parent's slot, before any child of the epoch is applied), fittest first
    /// (child order on a tie), added up by [`combine`].
    fn combine_improving_nudges(
        &self,
        children: &[Child],
        outcomes: &[&Outcome],
        max_points: usize,
    ) -> Option<Genome> {
        let mut improving: Vec<(usize, &Child)> = children
            .iter()
            .enumerate()
            .filter(|(k, c)| {
                c.nudge
                    && !c.combined
                    && outcomes[*k].is_fitter_than(&self.population[c.dominant_parent].outcome)
            })
            .collect();
        // Nudges of one epoch share one base (the island's best, or the run's under `shared`).
        let slot = improving.first()?.1.dominant_parent;
        improving.retain(|(_, c)| c.dominant_parent == slot);
        let base = &self.population[slot].genome;
        // A stable sort, so ties keep child order.
        improving.sort_by(|(a, _), (b, _)| outcomes[*b].rank().total_cmp(&outcomes[*a].rank()));
        let genomes: Vec<&Genome> = improving.iter().map(|(_, c)| &c.genome).collect();
        let combined = combine(base, &genomes, max_points);
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

    /// Slots from the fittest to the least fit (the lower slot first on a tie).
    pub fn ranked_slots(&self) -> Vec<usize> {
        let pop = &self.population;
        let mut order: Vec<usize> = (0..pop.len()).collect();
        order.sort_by(|&a, &b| {
            (pop[b].outcome.rank())
                .total_cmp(&pop[a].outcome.rank())
                .then(a.cmp(&b))
        });
        order
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

    #[cfg(test)]
    pub fn rng_mut(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }
}

#[cfg(test)]
mod tests {
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

    fn breeding(variation: Variation) -> Breeding {
        Breeding {
            mutation: MutationParams::default(),
            variation,
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
        let b = breeding(Variation {
            local_search: LocalSearchParams {
                fraction: 0.5,
                points: 0,
                probability: 1.0,
                step: 0.01,
                insertion: 0.0,
                shared: false,
                combine: false,
            },
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
        let b = breeding(Variation {
            local_search: LocalSearchParams {
                fraction: 0.5,
                shared: true,
                ..Default::default()
            },
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
            let b = breeding(Variation {
                local_search: LocalSearchParams {
                    fraction: 1.0,
                    points,
                    ..Default::default()
                },
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
        let b = breeding(Variation {
            local_search: LocalSearchParams {
                fraction: 1.0,
                combine: true,
                ..Default::default()
            },
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

    #[test]
    fn the_step_adapts_to_crossover_children_only() {
        use crate::search::variation::{StepAdaptation, StepRule};
        let mut isl = island(0, &[0.1, 0.2], &[-5.0, -3.0]);
        let b = breeding(Variation {
            step_adaptation: StepAdaptation {
                rule: StepRule::OneFifth,
                ..Default::default()
            },
            ..Default::default()
        });
        // 1 of 2 crossover children succeeds (50 % > 1/5); a successful nudge does not count.
        let mut nudge = child(1, 0.3);
        nudge.nudge = true;
        isl.apply(
            vec![child(0, 0.9), child(1, 0.8), nudge],
            vec![
                (TaskId(1), scored(-4.0)),
                (TaskId(2), scored(-9.0)),
                (TaskId(3), scored(-0.5)),
            ],
            None,
        );
        isl.breed(1, &b, DIMS, None);
        assert_eq!(isl.step_scale(), 1.2);
        // Then an epoch with only failures shrinks it back.
        let children = vec![child(0, 0.1)];
        isl.apply(children, vec![(TaskId(4), failed())], None);
        isl.breed(1, &b, DIMS, None);
        assert_eq!(isl.step_scale(), 1.0);
    }
}
