//! The run loop: initial populations, then epochs (breeding and evaluation, migration, a
//! resolution switch when progress stalls) until a stopping rule holds, with everything written as
//! it happens. What changes the search is in `search.rs`, one batch of evaluations in `batch.rs`.

pub(crate) mod batch;
mod search;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use amorph::task::Scene;
use tracing::info;

use crate::config::RunConfig;
use crate::evaluator::{Evaluator, EvaluatorError};
use crate::progress::Progress;
use crate::results::ResultWriter;
use crate::search::DiversityLog;
use crate::search::Front;
use crate::store::{RunStore, StoreError};
use crate::summary::{RunSummary, StopReason};
use crate::verification::VerificationError;
use search::{Search, record_epoch};

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Evaluator(#[from] EvaluatorError),
    #[error("results: {0}")]
    Results(#[from] std::io::Error),
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error("resume: {0}")]
    Replay(String),
}

impl From<VerificationError> for RunError {
    fn from(e: VerificationError) -> Self {
        match e {
            VerificationError::Evaluator(e) => Self::Evaluator(e),
            VerificationError::Store(e) => Self::Store(e),
        }
    }
}

/// What a run needs besides its config and evaluator.
#[derive(Clone, Copy, Debug)]
pub struct RunContext<'a> {
    /// Every evaluation, epoch and migration goes here as it happens; a resumed run replays from it.
    pub store: &'a RunStore,
    /// Set (e.g. by Ctrl-C) to stop at the next epoch boundary or mid-batch.
    pub shutdown: &'a AtomicBool,
    pub progress: &'a Progress,
}

pub type Result<T> = std::result::Result<T, RunError>;

/// Runs a whole search with the given evaluator. Results are written as the run goes (history per
/// epoch, best design when it improves, every evaluation to the run store) so an interrupted run
/// keeps what it finished; a store holding an earlier session's evaluations is replayed first.
pub fn run(
    config: &RunConfig,
    evaluator: &mut dyn Evaluator,
    ctx: &RunContext<'_>,
) -> Result<RunSummary> {
    let schedule = &config.resolution;
    let scene = Arc::new(config.scene.clone());
    let mut writer = ResultWriter::create(config)?;
    let mut diversity = DiversityLog::create(writer.dir())?;
    let mut history = Vec::new();
    let mut search = Search::start(config, scene.clone(), evaluator, ctx)?;

    let stop = loop {
        let dims = schedule.dims(search.resolution.level);
        if let Some(reason) = stop_reason(config, &scene, &search, ctx.shutdown) {
            break reason;
        }
        let replacements = search.epoch(config, dims, evaluator, ctx)?;
        let rows = search.history_rows(&scene, dims, &replacements);
        for row in &rows {
            writer.history(row)?;
        }
        let migrations = search.migrate(config);
        record_epoch(&search, &migrations, &rows, dims, ctx.store)?;
        // An observer hears of the epoch once the store holds it.
        ctx.progress.history(&rows);
        history.extend(rows);
        diversity.record(
            search.ledger.epoch,
            search.ledger.evaluations,
            &search.islands,
            &scene,
            dims,
        )?;

        let best = search.best();
        writer.best_so_far(best, dims)?;
        let island_bests: Vec<Option<String>> = search
            .islands
            .iter()
            .map(|i| scene.headline(&i.best().outcome))
            .collect();
        let status = evaluator.status();
        ctx.progress.epoch(
            search.ledger.epoch,
            scene.headline(&best.outcome),
            dims,
            &island_bests,
            status.as_deref(),
        );
        info!(
            epoch = search.ledger.epoch,
            evaluations = search.ledger.evaluations,
            resolution = %dims,
            best = scene.headline(&best.outcome).as_deref().unwrap_or("-"),
            islands = ?island_bests,
            cluster = status.as_deref().unwrap_or("-"),
            "epoch done"
        );
        search.switch_if_stalled(config, evaluator, ctx)?;
    };

    let dims = schedule.dims(search.resolution.level);
    // The front is of every design evaluated (and checked) at the final resolution, from the
    // store: a resumed run's earlier sessions count too.
    let pareto = match search.islands[0].pareto() {
        Some(pareto) => {
            let stored = ctx.store.evaluations()?;
            let level = dims.to_string();
            let front = pareto.front(
                (stored.iter())
                    .filter(|(_, e)| e.resolution == level && !e.unchecked)
                    .map(|(task, e)| (*task, &e.outcome)),
            );
            let fittest = pareto.values(&search.best().outcome);
            Some(Front { fittest, ..front })
        }
        None => None,
    };
    let summary = RunSummary {
        stop,
        epochs: search.ledger.epoch,
        evaluations: search.ledger.evaluations,
        unchanged_children: search.unchanged_children,
        wall_seconds: search.clock.seconds(),
        dims,
        populations: search.islands.into_iter().map(|i| i.population).collect(),
        history,
        pareto,
    };
    writer.finish(&summary, &scene)?;
    ctx.progress.finish(&summary);
    Ok(summary)
}

fn stop_reason(
    config: &RunConfig,
    scene: &Scene,
    search: &Search,
    shutdown: &AtomicBool,
) -> Option<StopReason> {
    let budget = &config.budget;
    if shutdown.load(Ordering::Relaxed) {
        return Some(StopReason::Shutdown);
    }
    if search.switch_unaffordable
        || budget
            .evaluations
            .is_some_and(|max| search.ledger.evaluations >= max)
    {
        return Some(StopReason::EvaluationBudget);
    }
    // While replaying what an earlier session recorded, only that session's own stopping rules
    // apply: it went on, so this session goes on too.
    let replaying = search
        .replay_until
        .is_some_and(|last| search.ledger.epoch < last);
    if !replaying
        && budget
            .wall_seconds
            .is_some_and(|max| search.clock.seconds() >= max)
    {
        return Some(StopReason::WallTime);
    }
    // The task's stop rule, at the final resolution only (a coarse level's error is not the
    // design's).
    if let Some(target) = budget.target_rms_percent
        && search.resolution.is_final(&config.resolution)
        && scene.meets_target(&search.best().outcome, target)
    {
        return Some(StopReason::TargetReached);
    }
    None
}
