//! The coarse level judged on the finest grid (`resolution.stall_on_finest`): the check of the
//! run's best at the finest level, and the next epoch's children sent out beside it, kept if the
//! level goes on and dropped without a trace if the check ends it. The children do not depend on
//! the check, so the results are the same bits as checking alone; the workers the single check
//! would leave idle evaluate them meanwhile.

use amorph::genome::Genome;
use amorph::voxel::GridDims;
use tracing::info;

use super::super::batch::{Held, Part, evaluate_parts, settle};
use super::super::{Result, RunContext};
use super::{Search, genomes_of};
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::search::{Child, Island};
use crate::store::Purpose;
use crate::verification::{self, Evaluated};

/// Children bred and evaluated ahead of their epoch, beside a check at the finest level that does
/// not change them. The epoch takes them if it comes at this level; a switch drops them, and with
/// them every trace of their breeding: the islands (random streams, combinations) and the task
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
    /// rank the checks at this level have given. The next epoch's children go out with the
    /// check and wait in `overlap` for the stall rule's verdict.
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
        let affordable =
            (config.budget.evaluations).is_none_or(|max| self.ledger.evaluations < max);
        if !affordable || self.finest_checked.as_ref() == Some(&best.genome) {
            return Ok(self.checked_best);
        }
        let mut genomes = vec![Vec::new(); island + 1];
        genomes[island].push(best.genome.clone());
        let schedule = &config.resolution;
        let finest = schedule.finest();
        let mut parts = vec![Part::number(
            &mut self.ledger,
            &genomes,
            finest,
            Purpose::FinestCheck,
        )];
        let dims = schedule.dims(self.resolution.level);
        let islands_before = self.islands.clone();
        let next_task_before = self.ledger.next_task;
        let unchanged_before = self.unchanged_children;
        // The check is part of the budget the children share.
        let children = self.breed_children(config, dims, self.ledger.evaluations + 1);
        let ahead = genomes_of(&children);
        parts.push(Part::number(&mut self.ledger, &ahead, dims, Purpose::Child));
        let (mut batches, held) = evaluate_parts(&mut self.ledger, evaluator, parts, 1, ctx)?;
        if let Some(held) = held.into_iter().next() {
            let batch = batches.pop().expect("the children's part");
            self.overlap = Some(Overlap {
                dims,
                children,
                genomes: ahead,
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
        let (_, outcome) = &outcomes[island][0];
        info!(epoch = self.ledger.epoch, island, rank = outcome.rank(), resolution = %finest, "the run's best checked at the finest level");
        let genome = genomes
            .swap_remove(island)
            .pop()
            .expect("the checked genome");
        if outcome.rank() > self.checked_best {
            self.checked_best = outcome.rank();
        }
        self.finest_checked = Some(genome);
        Ok(self.checked_best)
    }

    /// Forgets children bred ahead of their epoch as if they had never been bred.
    pub(super) fn drop_overlap(&mut self, overlap: Overlap) {
        self.islands = overlap.islands_before;
        self.ledger.next_task = overlap.next_task_before;
        self.unchanged_children = overlap.unchanged_before;
    }
}
