//! The switch from one resolution level to the next once progress stalls there. It is a function
//! of the outcomes so far, so a replay switches where the recorded run did.

use amorph::genome::Genome;
use tracing::info;

use super::super::batch::evaluate_settled;
use super::super::{Result, RunContext};
use super::Search;
use crate::config::RunConfig;
use crate::evaluator::Evaluator;
use crate::store::Purpose;

impl Search {
    /// Moves to the next resolution once progress stalls there, re-evaluating every population.
    /// With less budget left than that re-evaluation, the run ends here (`switch_unaffordable`)
    /// rather than overshoot its budget or breed on at a level it would have left: a run resumed
    /// with a larger budget then switches where the run with that budget from the start did, and
    /// replays to the same bits.
    pub(in crate::run) fn switch_if_stalled(
        &mut self,
        config: &RunConfig,
        evaluator: &mut dyn Evaluator,
        ctx: &RunContext<'_>,
    ) -> Result<()> {
        let schedule = &config.resolution;
        let reevaluations: usize = self.islands.iter().map(|i| i.population.len()).sum();
        let watched = if schedule.stall_on_finest && !self.resolution.is_final(schedule) {
            self.check_on_finest(config, evaluator, ctx)?
        } else {
            self.progress()
        };
        let switch_affordable = config
            .budget
            .evaluations
            .is_none_or(|max| max.saturating_sub(self.ledger.evaluations) >= reevaluations as u64);
        let mut next = self.resolution.clone();
        let switch = next.observe(watched, self.ledger.evaluations, schedule);
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
        self.checked_best = f64::NEG_INFINITY;
        let dims = schedule.dims(self.resolution.level);
        info!(epoch = self.ledger.epoch, resolution = %dims, "re-evaluating at the next resolution (progress stalled, or resolution.latest_switch reached)");
        let genomes: Vec<Vec<Genome>> = (self.islands.iter())
            .map(|island| island.population.iter().map(|i| i.genome.clone()).collect())
            .collect();
        let outcomes = evaluate_settled(
            &mut self.ledger,
            evaluator,
            &genomes,
            dims,
            Purpose::Reevaluation,
            ctx,
        )?;
        for (island, outcomes) in self.islands.iter_mut().zip(outcomes) {
            island.at_resolution(dims);
            for (ind, (task, outcome)) in island.population.iter_mut().zip(outcomes) {
                ind.outcome = outcome;
                ind.task = task;
            }
        }
        Ok(())
    }
}
