//! Ask and tell: batches of genomes that a caller outside the search chooses (an optimizer of its
//! own, such as CMA-ES driven from Python) evaluated on the coordinator's workers, local and
//! remote, with the same verification and the same run store as a search's. Each batch is an
//! epoch of the store; its tasks are numbered in the order asked, so a caller that asks the same
//! batches again (the same optimizer and seed) after a stop resumes from the store: every genome
//! already evaluated takes its stored outcome.

use std::sync::atomic::Ordering;
use std::time::Instant;

use amorph::genome::Genome;
use amorph::task::Outcome;
use amorph::voxel::GridDims;

use crate::config::RunConfig;
use crate::evaluator::EvaluatorError;
use crate::job::{Coordinator, JobError, JobOptions};
use crate::run::batch::{Ledger, evaluate_settled};
use crate::run::{RunContext, RunError};
use crate::store::{EpochRecord, Purpose};

/// A coordinator that evaluates what it is asked, batch by batch.
#[derive(Debug)]
pub struct AskedRun {
    coordinator: Coordinator,
    options: JobOptions,
    ledger: Ledger,
    /// The best fitness asked so far, for the store's epoch rows.
    best: Option<f64>,
    /// Wall seconds an earlier session of this run had used.
    earlier_seconds: f64,
    started: Instant,
}

impl AskedRun {
    /// Starts the coordinator (server, local workers, run store) for `config`'s scene and cluster.
    /// With `StoreMode::Resume` the stored evaluations are taken again where the same genome is
    /// asked under the same task number.
    pub fn start(config: &RunConfig, options: JobOptions) -> Result<Self, JobError> {
        let coordinator = Coordinator::start(config, &options)?;
        let replay = coordinator.store.evaluations().map_err(JobError::Store)?;
        let earlier_seconds = coordinator
            .store
            .recorded_wall_seconds()
            .map_err(JobError::Store)?;
        Ok(Self {
            coordinator,
            options,
            ledger: Ledger {
                replay,
                ..Ledger::default()
            },
            best: None,
            earlier_seconds,
            started: Instant::now(),
        })
    }

    /// Where workers connect.
    pub fn url(&self) -> &str {
        &self.coordinator.url
    }

    /// The run store's path.
    pub fn store_path(&self) -> &std::path::Path {
        self.coordinator.store.path()
    }

    /// Evaluations asked so far, stored ones taken again included.
    pub fn evaluations(&self) -> u64 {
        self.ledger.evaluations
    }

    /// Evaluates `genomes` at `dims` and returns their outcomes in order, once every outside
    /// worker's outcome among them is checked. A stop (`JobOptions::shutdown`) ends the batch
    /// early with [`EvaluatorError::Stopped`]; what finished is in the store.
    pub fn evaluate(
        &mut self,
        genomes: &[Genome],
        dims: GridDims,
    ) -> Result<Vec<Outcome>, RunError> {
        if self.options.shutdown.load(Ordering::Relaxed) {
            return Err(EvaluatorError::Stopped("stopped before the batch".into()).into());
        }
        let ctx = RunContext {
            store: &self.coordinator.store,
            shutdown: &self.options.shutdown,
            progress: &self.options.progress,
        };
        let batch = evaluate_settled(
            &mut self.ledger,
            &mut self.coordinator.evaluator,
            &[genomes.to_vec()],
            dims,
            Purpose::Asked,
            &ctx,
        )?;
        self.ledger.epoch += 1;
        let outcomes: Vec<Outcome> = batch
            .into_iter()
            .flatten()
            .map(|(_, outcome)| outcome)
            .collect();
        for fitness in outcomes.iter().filter_map(Outcome::fitness) {
            self.best = Some(self.best.map_or(fitness, |b| b.max(fitness)));
        }
        self.coordinator.store.record_epoch(&EpochRecord {
            epoch: self.ledger.epoch,
            evaluations: self.ledger.evaluations,
            wall_seconds: self.earlier_seconds + self.started.elapsed().as_secs_f64(),
            resolution: dims.to_string(),
            best_fitness: self.best,
            populations: Vec::new(),
            migrations: &[],
            history: &[],
        })?;
        Ok(outcomes)
    }

    /// Stops the coordinator. Outside workers are told the run finished (so they exit) unless it
    /// was stopped, when they wait to serve its resumption.
    pub fn close(self) {
        let finished = !self.options.shutdown.load(Ordering::Relaxed);
        self.coordinator.close(finished);
    }
}
