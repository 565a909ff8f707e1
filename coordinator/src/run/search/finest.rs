//! The coarse level judged on the finest grid (`resolution.stall_on_finest`): the check of the
//! run's best at the finest level, and the next epoch's children sent out beside it
//! (`resolution.overlap_finest_checks`), kept if the level goes on and dropped without a trace if
//! the check ends it.

use amorph::genome::Genome;
use amorph::voxel::GridDims;
use tracing::info;

use super::super::batch::{Held, Part, evaluate_parts, settle};
use super::super::{Result, RunContext};
use super::{Search, genomes_of};
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::search::{Child, Individual, Island};
use crate::store::Purpose;
use crate::verification::{self, Evaluated};

/// Children bred and evaluated ahead of their epoch, beside a check at the finest level that does
/// not change them. The epoch takes them if it comes at this level; a switch drops them, and with
/// them every trace of their breeding: the islands (random streams, step adaptation) and the task
/// numbers go back to what they were, and their outcomes were never stored or counted.
pub(super) struct Overlap {
    pub(super) dims: GridDims,
    pub(super) children: Vec<Vec<Child>>,
    pub(super) genomes: Vec<Vec<Genome>>,
    pub(super) batch: Vec<Vec<Evaluated>>,
    pub(super) held: Held,
    islands_before: Vec<Island>,
    next_task_before: u64,
    /// The children dropped as copies of their parent so far (`search.skip_unchanged`), before
    /// these were bred.
    unchanged_before: u64,
}

impl Search {
    /// Evaluates the run's best at the finest level when it is not the genome checked last
    /// (and the budget has room for it), as the task of the island holding it; returns the best
    /// rank the checks at this level have given. With `resolution.overlap_finest_checks` the
    /// next epoch's children go out with the check, so the workers the single check leaves idle
    /// evaluate them meanwhile; they wait in `overlap` for the stall rule's verdict.
    pub(super) fn check_on_finest(
        &mut self,
        config: &RunConfig,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<f64> {
        let best = self.best();
        let island = (self.islands.iter())
            .position(|i| std::ptr::eq(i.best(), best))
            .expect("the run's best is an island's best");
        let affordable = (config.raw.budget.evaluations).is_none_or(|max| self.evaluations < max);
        if !affordable || self.finest_checked.as_ref() == Some(&best.genome) {
            return Ok(self.finest_best());
        }
        let mut genomes = vec![Vec::new(); island + 1];
        genomes[island].push(best.genome.clone());
        let schedule = &config.raw.resolution;
        let finest = schedule.finest();
        let mut parts = vec![Part::number(self, &genomes, finest, Purpose::FinestCheck)];
        let ahead = schedule.overlap_finest_checks.then(|| {
            let dims = schedule.dims(self.resolution.level);
            let islands_before = self.islands.clone();
            let next_task_before = self.next_task;
            let unchanged_before = self.unchanged_children;
            // The check is part of the budget the children share.
            let children = self.breed_children(config, dims, self.evaluations + 1);
            let genomes = genomes_of(&children);
            let before = (islands_before, next_task_before, unchanged_before);
            (dims, children, genomes, before)
        });
        if let Some((dims, _, genomes, ..)) = &ahead {
            parts.push(Part::number(self, genomes, *dims, Purpose::Child));
        }
        let (mut batches, held) = evaluate_parts(self, evaluator, parts, 1, ctx)?;
        if let (Some((dims, children, genomes, before)), Some(held)) =
            (ahead, held.into_iter().next())
        {
            let (islands_before, next_task_before, unchanged_before) = before;
            let batch = batches.pop().expect("the children's part");
            self.overlap = Some(Overlap {
                dims,
                children,
                genomes,
                batch,
                held,
                islands_before,
                next_task_before,
                unchanged_before,
            });
        }
        let checked = batches.pop().expect("the check's part");
        let outcomes = settle(
            checked,
            &genomes,
            finest,
            evaluator,
            ctx,
            &verification::all_decide,
        )?;
        let (task, outcome) = &outcomes[island][0];
        info!(epoch = self.epoch, island, rank = outcome.rank(), resolution = %finest, "the run's best checked at the finest level");
        let genome = genomes
            .swap_remove(island)
            .pop()
            .expect("the checked genome");
        if outcome.rank() > self.finest_best() {
            let design = Individual {
                genome: genome.clone(),
                outcome: outcome.clone(),
                task: *task,
            };
            self.checked_best = Some((island, design));
        }
        self.finest_checked = Some(genome);
        Ok(self.finest_best())
    }

    /// The best rank the checks at this level have given.
    fn finest_best(&self) -> f64 {
        (self.checked_best.as_ref()).map_or(f64::NEG_INFINITY, |(_, d)| d.outcome.rank())
    }

    /// Forgets children bred ahead of their epoch as if they had never been bred.
    pub(super) fn drop_overlap(&mut self, overlap: Overlap) {
        self.islands = overlap.islands_before;
        self.next_task = overlap.next_task_before;
        self.unchanged_children = overlap.unchanged_before;
    }
}

/// Puts `design`, already scored at the level `island` has just been re-evaluated at, in place of
/// the island's worst individual, unless the island holds it already (its re-evaluation gave the
/// same bits) or it is not fitter than that worst. Returns the slot it took.
pub(super) fn carry_checked(island: &mut Island, design: Individual) -> Option<usize> {
    if island.population.iter().any(|i| i.genome == design.genome) {
        return None;
    }
    let worst = island.worst_index();
    if !design
        .outcome
        .is_fitter_than(&island.population[worst].outcome)
    {
        return None;
    }
    island.population[worst] = design;
    Some(worst)
}
