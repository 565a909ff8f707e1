//! The switch from one resolution level to the next once progress stalls there, and islands on
//! demand splitting the one population once it stalls at the finest level. Both are functions of
//! the outcomes so far, so a replay switches and splits where the recorded run did.

use amorph::genome::Genome;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracing::info;

use super::super::batch::evaluate_settled;
use super::super::{Result, RunContext};
use super::Search;
use super::finest::carry_checked;
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::ids::IslandId;
use crate::search::{Individual, Island, merge_order, split_island};
use crate::store::Purpose;

impl Search {
    /// Moves to the next resolution once progress stalls there, re-evaluating every population
    /// (or, with `resolution.merge_islands`, the islands' best in turn as one population of
    /// `resolution.merged_population`). With less budget left than that re-evaluation, the run
    /// ends here (`switch_unaffordable`) rather than overshoot its budget or breed on at a level
    /// it would have left: a run resumed with a larger budget then switches where the run with
    /// that budget from the start did, and replays to the same bits.
    pub(in crate::run) fn switch_if_stalled(
        &mut self,
        config: &RunConfig,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<()> {
        let schedule = &config.raw.resolution;
        let merge = schedule.merge_islands && self.islands.len() > 1;
        let merged = schedule
            .merged_population
            .unwrap_or(config.raw.search.population);
        let individuals: usize = self.islands.iter().map(|i| i.population.len()).sum();
        let reevaluations = if merge {
            individuals.min(merged)
        } else {
            individuals
        } as u64;
        let watched = if schedule.stall_on_finest && !self.resolution.is_final(schedule) {
            self.check_on_finest(config, evaluator, ctx)?
        } else {
            self.best().outcome.rank()
        };
        let switch_affordable = config
            .raw
            .budget
            .evaluations
            .is_none_or(|max| max.saturating_sub(self.evaluations) >= reevaluations);
        let mut next = self.resolution.clone();
        let switch = next.observe(watched, self.evaluations, schedule);
        if switch && !switch_affordable {
            self.switch_unaffordable = true;
            return Ok(());
        }
        self.resolution = next;
        if !switch {
            return Ok(());
        }
        self.breed_for_level(config);
        if let Some(overlap) = self.overlap.take() {
            self.drop_overlap(overlap);
        }
        self.finest_checked = None;
        // Its score is at the finest level: it can only join a population scored there.
        let checked_best = (self.checked_best.take())
            .filter(|_| schedule.carry_checked_best && self.resolution.is_final(schedule));
        let carried: Vec<Vec<(usize, usize)>> = if merge {
            vec![merge_order(&self.islands, merged)]
        } else {
            (self.islands.iter().enumerate())
                .map(|(i, island)| (0..island.population.len()).map(|s| (i, s)).collect())
                .collect()
        };
        let dims = schedule.dims(self.resolution.level);
        info!(epoch = self.epoch, resolution = %dims, merge, "re-evaluating at the next resolution (progress stalled, or resolution.latest_switch reached)");
        let genomes: Vec<Vec<Genome>> = carried
            .iter()
            .map(|group| {
                (group.iter())
                    .map(|&(i, s)| self.islands[i].population[s].genome.clone())
                    .collect()
            })
            .collect();
        let outcomes =
            evaluate_settled(self, evaluator, &genomes, dims, Purpose::Reevaluation, ctx)?;
        if merge {
            // The merged island draws from the stream after the islands' own (stream 0 is
            // migration's, 1..=islands the islands'), so the run stays a function of its seed.
            let mut rng = ChaCha8Rng::seed_from_u64(config.raw.seed);
            rng.set_stream(config.raw.search.islands as u64 + 1);
            let population = (genomes.into_iter().flatten())
                .zip(outcomes.into_iter().flatten())
                .map(|(genome, (task, outcome))| Individual {
                    genome,
                    outcome,
                    task,
                })
                .collect();
            self.children_per_island *= self.islands.len();
            self.islands = vec![Island::from_evaluated(IslandId(0), rng, population)];
        } else {
            for (island, outcomes) in self.islands.iter_mut().zip(outcomes) {
                for (ind, (task, outcome)) in island.population.iter_mut().zip(outcomes) {
                    ind.outcome = outcome;
                    ind.task = task;
                }
            }
        }
        if let Some((island, design)) = checked_best {
            // Merged islands are one: the design joins it wherever it was checked.
            let island = island.min(self.islands.len() - 1);
            if let Some(slot) = carry_checked(&mut self.islands[island], design) {
                info!(
                    epoch = self.epoch,
                    island, slot, "the best design checked at the finest level carried into it"
                );
            }
        }
        Ok(())
    }

    /// Islands on demand: splits the one population into the configured islands once the run's
    /// best at the finest resolution has stalled for `search.split_after_stall` epochs. The split
    /// islands draw from the streams after merging's (`islands + 2` onwards).
    pub(in crate::run) fn split_if_stalled(&mut self, config: &RunConfig) {
        let raw = &config.raw;
        if !self.resolution.is_final(&raw.resolution)
            || !(self.split).observe(self.best().outcome.rank(), raw.resolution.min_improvement)
        {
            return;
        }
        // Children bred ahead wait only beside a coarse level's finest check; the switch to the
        // finest level drops them, so none can be held from the islands before the split.
        debug_assert!(self.overlap.is_none(), "children held at the finest level");
        let whole = self.islands.pop().expect("an unsplit run has one island");
        let islands = raw.search.islands;
        info!(
            epoch = self.epoch,
            islands,
            "splitting the population into islands (progress stalled at the finest resolution)"
        );
        self.islands = split_island(whole, islands, raw.seed, islands as u64 + 2);
        self.children_per_island = raw.search.children_per_epoch;
    }
}
