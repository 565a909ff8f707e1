//! The run loop: initial populations, epochs of breeding and evaluation, migration, resolution
//! switches, and the stopping rules.

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tracing::info;

use crate::config::RunConfig;
use crate::evaluator::{Completion, Evaluator, EvaluatorError, Origin, Task};
use crate::ids::{IslandId, TaskId};
use crate::progress::Progress;
use crate::results::ResultWriter;
use crate::search::{Breeding, DiversityLog, Individual, Island, ResolutionState, migrate};
use crate::store::{
    EpochRecord, EvaluationRecord, MigrationRecord, Purpose, RunStore, StoreError, StoredEvaluation,
};
use crate::summary::{HistoryRow, RunSummary, StopReason, fittest};
use crate::verification::{self, Decisive, EARLIER_SESSION, Evaluated, VerificationError};

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

/// The state of a search between epochs.
struct Search {
    islands: Vec<Island>,
    migration_rng: ChaCha8Rng,
    resolution: ResolutionState,
    epoch: usize,
    evaluations: u64,
    next_task: u64,
    /// Outcomes of an earlier, interrupted session of this run, by task id (see [`crate::store`]).
    replay: HashMap<u64, StoredEvaluation>,
    /// The last epoch that session recorded: up to it the replay must match the store exactly.
    replay_until: Option<usize>,
    clock: RunClock,
}

/// Wall time of the run across sessions: what earlier sessions used plus this session's time.
struct RunClock {
    started: Instant,
    earlier: f64,
}

impl RunClock {
    fn seconds(&self) -> f64 {
        self.earlier + self.started.elapsed().as_secs_f64()
    }
}

/// Runs a whole search with the given evaluator. Results are written as the run goes (history per
/// epoch, best design when it improves, every evaluation to the run store) so an interrupted run
/// keeps what it finished; a store holding an earlier session's evaluations is replayed first.
pub fn run(
    config: &RunConfig,
    evaluator: &mut dyn Evaluator,
    ctx: &RunContext<'_>,
) -> Result<RunSummary> {
    let raw = &config.raw;
    let progress = ctx.progress;
    let scene = Arc::new(raw.scene.clone());
    let breeding = Breeding {
        mutation: raw.search.mutation.clone(),
        variation: raw.search.variation(),
        scene: scene.clone(),
    };
    let schedule = &raw.resolution;
    let mut writer = ResultWriter::create(config)?;
    let mut diversity = DiversityLog::create(writer.dir())?;
    let mut history = Vec::new();

    // Island i draws from stream i + 1 of the run seed; stream 0 drives migration.
    let island_rng = |i: usize| {
        let mut rng = ChaCha8Rng::seed_from_u64(raw.seed);
        rng.set_stream(i as u64 + 1);
        rng
    };
    let mut migration_rng = ChaCha8Rng::seed_from_u64(raw.seed);
    migration_rng.set_stream(0);

    let mut rngs: Vec<ChaCha8Rng> = (0..raw.search.islands).map(island_rng).collect();
    let initial: Vec<Vec<Genome>> = rngs
        .iter_mut()
        .map(|rng| {
            Island::initial_genomes(
                rng,
                raw.search.population,
                raw.search.initial_points,
                &breeding,
            )
        })
        .collect();
    let replay = ctx.store.evaluations()?;
    let replay_until = ctx.store.last_epoch()?;
    if !replay.is_empty() {
        info!(evaluations = replay.len(), last_epoch = ?replay_until, "resuming: replaying the stored run");
    }
    let mut search = Search {
        islands: Vec::new(),
        migration_rng,
        resolution: ResolutionState::new(),
        epoch: 0,
        evaluations: 0,
        next_task: 0,
        replay,
        replay_until,
        clock: RunClock {
            started: Instant::now(),
            earlier: ctx.store.recorded_wall_seconds()?,
        },
    };
    let dims = schedule.dims(0);
    let batch = evaluate_all(
        &mut search,
        evaluator,
        &initial,
        dims,
        Purpose::Initial,
        ctx,
    )?;
    let outcomes = settle(
        batch,
        &initial,
        dims,
        evaluator,
        ctx,
        &verification::all_decide,
    )?;
    search.islands = initial
        .into_iter()
        .zip(outcomes)
        .zip(rngs)
        .enumerate()
        .map(|(i, ((genomes, outcomes), rng))| {
            let population = genomes
                .into_iter()
                .zip(outcomes)
                .map(|(genome, (task, outcome))| Individual {
                    genome,
                    outcome,
                    task,
                })
                .collect();
            Island::from_evaluated(IslandId(i as u32), rng, population)
        })
        .collect();

    let budget = &raw.budget;
    let stop = loop {
        let dims = schedule.dims(search.resolution.level);
        if let Some(reason) = stop_reason(config, &scene, &search, ctx.shutdown) {
            break reason;
        }
        // Breed every island's epoch from its snapshot, evaluate all children as one batch.
        // The last epoch is shortened (spread over the islands) so the run ends exactly on budget.
        let islands = search.islands.len();
        let left = budget
            .evaluations
            .map_or(u64::MAX, |max| max.saturating_sub(search.evaluations));
        let children: Vec<_> = search
            .islands
            .iter_mut()
            .enumerate()
            .map(|(i, island)| {
                let share = left / islands as u64 + u64::from((i as u64) < left % islands as u64);
                let count = (raw.search.children_per_epoch as u64).min(share) as usize;
                island.breed(count, &breeding, dims)
            })
            .collect();
        let genomes: Vec<Vec<Genome>> = children
            .iter()
            .map(|c| c.iter().map(|c| c.genome.clone()).collect())
            .collect();
        let batch = evaluate_all(&mut search, evaluator, &genomes, dims, Purpose::Child, ctx)?;
        // A child's outcome decides when it would replace its dominant parent.
        let winners = |batch: &[Vec<Evaluated>]| -> Vec<Vec<bool>> {
            search
                .islands
                .iter()
                .zip(&children)
                .zip(batch)
                .map(|((island, children), group)| {
                    let outcomes: Vec<&Outcome> = group.iter().map(|e| &e.outcome).collect();
                    island.winners(children, &outcomes)
                })
                .collect()
        };
        let outcomes = settle(batch, &genomes, dims, evaluator, ctx, &winners)?;
        search.epoch += 1;
        let wall = search.clock.seconds();
        for ((island, children), outcomes) in search.islands.iter_mut().zip(children).zip(outcomes)
        {
            let replacements = island.apply(children, outcomes);
            let row = history_row(
                &scene,
                island,
                search.epoch,
                search.evaluations,
                wall,
                dims,
                replacements,
            );
            writer.history(&row)?;
            history.push(row);
        }

        let migration = &raw.search.migration;
        let mut migrations = Vec::new();
        if migration.interval > 0 && search.epoch.is_multiple_of(migration.interval) {
            for event in migrate(&mut search.islands, migration, &mut search.migration_rng) {
                info!(epoch = search.epoch, from = %event.from, to = %event.to, emigrant = event.emigrant, replaced = ?event.replaced, task = %event.task, "migration");
                migrations.push(MigrationRecord {
                    from: event.from.0,
                    to: event.to.0,
                    emigrant_slot: event.emigrant,
                    replaced_slot: event.replaced,
                    task_id: event.task.0,
                });
            }
        }
        record_epoch(&search, &migrations, dims, ctx.store)?;
        diversity.record(
            search.epoch,
            search.evaluations,
            &search.islands,
            &scene,
            dims,
        )?;

        let best = best_of(&search.islands);
        writer.best_so_far(best, dims)?;
        let island_bests: Vec<Option<String>> = search
            .islands
            .iter()
            .map(|i| scene.headline(&i.best().outcome))
            .collect();
        let status = evaluator.status();
        progress.epoch(
            search.epoch,
            scene.headline(&best.outcome),
            dims,
            &island_bests,
            status.as_deref(),
        );
        info!(
            epoch = search.epoch,
            evaluations = search.evaluations,
            resolution = %dims,
            best = scene.headline(&best.outcome).as_deref().unwrap_or("-"),
            islands = ?island_bests,
            cluster = status.as_deref().unwrap_or("-"),
            "epoch done"
        );

        // A switch re-evaluates every population; with less budget left than that, the run ends at
        // the current level rather than overshoot its evaluation budget.
        let population_total: u64 = search
            .islands
            .iter()
            .map(|i| i.population.len() as u64)
            .sum();
        let switch_affordable = budget
            .evaluations
            .is_none_or(|max| max.saturating_sub(search.evaluations) >= population_total);
        if switch_affordable && search.resolution.observe(best.outcome.rank(), schedule) {
            let dims = schedule.dims(search.resolution.level);
            info!(epoch = search.epoch, resolution = %dims, "progress stalled: re-evaluating at the next resolution");
            let genomes: Vec<Vec<Genome>> = search
                .islands
                .iter()
                .map(|i| i.population.iter().map(|ind| ind.genome.clone()).collect())
                .collect();
            let batch = evaluate_all(
                &mut search,
                evaluator,
                &genomes,
                dims,
                Purpose::Reevaluation,
                ctx,
            )?;
            let outcomes = settle(
                batch,
                &genomes,
                dims,
                evaluator,
                ctx,
                &verification::all_decide,
            )?;
            for (island, outcomes) in search.islands.iter_mut().zip(outcomes) {
                for (ind, (task, outcome)) in island.population.iter_mut().zip(outcomes) {
                    ind.outcome = outcome;
                    ind.task = task;
                }
            }
        }
    };

    let dims = schedule.dims(search.resolution.level);
    let summary = RunSummary {
        stop,
        epochs: search.epoch,
        evaluations: search.evaluations,
        wall_seconds: search.clock.seconds(),
        dims,
        populations: search.islands.into_iter().map(|i| i.population).collect(),
        history,
    };
    writer.finish(&summary, &scene)?;
    progress.finish(&summary);
    Ok(summary)
}

fn stop_reason(
    config: &RunConfig,
    scene: &Scene,
    search: &Search,
    shutdown: &AtomicBool,
) -> Option<StopReason> {
    let budget = &config.raw.budget;
    if shutdown.load(Ordering::Relaxed) {
        return Some(StopReason::Shutdown);
    }
    if budget
        .evaluations
        .is_some_and(|max| search.evaluations >= max)
    {
        return Some(StopReason::EvaluationBudget);
    }
    // While replaying what an earlier session recorded, only that session's own stopping rules
    // apply: it went on, so this session goes on too.
    let replaying = search.replay_until.is_some_and(|last| search.epoch < last);
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
        && search.resolution.is_final(&config.raw.resolution)
        && scene.meets_target(&best_of(&search.islands).outcome, target)
    {
        return Some(StopReason::TargetReached);
    }
    None
}

/// Evaluates one batch of genomes per island as a single evaluator call, returning the outcomes
/// (with their task ids) grouped the same way. Tasks whose outcome a resumed run's store already
/// holds take it from there; every new outcome is stored the moment it arrives. Outside workers'
/// outcomes are still claims: [`settle`] them before use.
fn evaluate_all(
    search: &mut Search,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    purpose: Purpose,
    ctx: &RunContext<'_>,
) -> Result<Vec<Vec<Evaluated>>> {
    let epoch = match purpose {
        Purpose::Child => search.epoch + 1,
        Purpose::Initial | Purpose::Reevaluation => search.epoch,
    };
    let resolution = dims.to_string();
    let mut tasks = Vec::new();
    let mut islands = Vec::new();
    for (island, batch) in genomes.iter().enumerate() {
        for genome in batch {
            search.next_task += 1;
            tasks.push(Task {
                id: TaskId(search.next_task),
                genome: genome.clone(),
                dims,
            });
            islands.push(island as u32);
        }
    }

    let mut evaluated: Vec<Option<Evaluated>> = vec![None; tasks.len()];
    let mut fresh = Vec::new();
    let mut fresh_slots = Vec::new();
    for (slot, task) in tasks.iter().enumerate() {
        let stored = search.replay.remove(&task.id.0).filter(|s| {
            s.resolution == resolution
                && serde_json::to_string(&task.genome).is_ok_and(|g| g == s.genome_json)
        });
        match stored {
            Some(s) => {
                evaluated[slot] = Some(Evaluated {
                    task: task.id,
                    outcome: s.outcome,
                    claimant: s.unchecked.then_some(EARLIER_SESSION),
                });
                ctx.progress.evaluated();
            }
            None => {
                fresh.push(task.clone());
                fresh_slots.push(slot);
            }
        }
    }

    if !fresh.is_empty() {
        let store_error: Mutex<Option<StoreError>> = Mutex::new(None);
        let on_done = |task: &Task, done: &Completion| {
            ctx.progress.evaluated();
            let record = EvaluationRecord {
                task_id: task.id.0,
                epoch,
                island: islands[fresh_slots[done.slot]],
                purpose,
                resolution: resolution.clone(),
                genome: &task.genome,
                outcome: &done.outcome,
                worker: &done.worker,
                wall_seconds: done.wall_seconds,
                unchecked: matches!(done.origin, Origin::Claim(_)),
            };
            if let Err(e) = ctx.store.record_evaluation(&record) {
                let mut first = store_error.lock().unwrap_or_else(|e| e.into_inner());
                first.get_or_insert(e);
            }
        };
        let results = evaluator.evaluate(&fresh, &on_done)?;
        if let Some(e) = store_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e.into());
        }
        for (slot, done) in fresh_slots.iter().zip(results) {
            evaluated[*slot] = Some(Evaluated {
                task: tasks[*slot].id,
                outcome: done.outcome,
                claimant: match done.origin {
                    Origin::Claim(w) => Some(w),
                    Origin::Trusted | Origin::GaveUp => None,
                },
            });
        }
        for (task, worker, message) in evaluator.take_worker_errors() {
            ctx.store.record_task_error(task.0, &worker, &message)?;
        }
    }
    search.evaluations += tasks.len() as u64;

    let mut evaluated = evaluated
        .into_iter()
        .map(|e| e.expect("every task has an outcome"));
    Ok(genomes
        .iter()
        .map(|g| evaluated.by_ref().take(g.len()).collect())
        .collect())
}

/// The outcomes of a batch once every outside worker's claim that `decisive` marks is checked
/// (`verification.rs`), each check recorded in the run store.
fn settle(
    mut batch: Vec<Vec<Evaluated>>,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    evaluator: &mut dyn Evaluator,
    ctx: &RunContext<'_>,
    decisive: Decisive<'_>,
) -> Result<Vec<Vec<(TaskId, Outcome)>>> {
    verification::confirm(
        &mut batch,
        genomes,
        dims,
        evaluator,
        decisive,
        &mut |claim, verdict| {
            ctx.store.record_check(
                claim.task.id.0,
                &claim.claimant.to_string(),
                &claim.outcome,
                verdict,
            )
        },
    )?;
    Ok(batch
        .into_iter()
        .map(|g| g.into_iter().map(|e| (e.task, e.outcome)).collect())
        .collect())
}

/// Stores the end of an epoch. While replaying, first checks the replayed populations against the
/// ones the earlier session recorded: any difference means the store is not this run's.
fn record_epoch(
    search: &Search,
    migrations: &[MigrationRecord],
    dims: GridDims,
    store: &RunStore,
) -> Result<()> {
    let populations: Vec<Vec<(u64, Option<f64>)>> = search
        .islands
        .iter()
        .map(|i| {
            i.population
                .iter()
                .map(|ind| (ind.task.0, ind.outcome.fitness()))
                .collect()
        })
        .collect();
    if search.replay_until.is_some_and(|last| search.epoch <= last) {
        let stored = store.population(search.epoch)?;
        let replayed: Vec<Vec<u64>> = populations
            .iter()
            .map(|p| p.iter().map(|&(t, _)| t).collect())
            .collect();
        if stored != replayed {
            return Err(RunError::Replay(format!(
                "the replayed populations of epoch {} differ from the ones {} recorded",
                search.epoch,
                store.path().display()
            )));
        }
    }
    store.record_epoch(&EpochRecord {
        epoch: search.epoch,
        evaluations: search.evaluations,
        wall_seconds: search.clock.seconds(),
        resolution: dims.to_string(),
        best_fitness: best_of(&search.islands).outcome.fitness(),
        populations,
        migrations,
    })?;
    Ok(())
}

fn best_of(islands: &[Island]) -> &Individual {
    fittest(islands.iter().map(|i| i.best()))
}

fn history_row(
    scene: &Scene,
    island: &Island,
    epoch: usize,
    evaluations: u64,
    wall_seconds: f64,
    dims: GridDims,
    replacements: usize,
) -> HistoryRow {
    let best = island.best();
    let valid: Vec<f64> = island
        .population
        .iter()
        .filter_map(|i| i.outcome.fitness())
        .collect();
    HistoryRow {
        epoch,
        evaluations,
        wall_seconds,
        resolution: dims.to_string(),
        island: island.id.0,
        best_fitness: best.outcome.fitness(),
        best_figure: scene.figure(&best.outcome),
        mean_fitness: (!valid.is_empty()).then(|| valid.iter().sum::<f64>() / valid.len() as f64),
        replacements,
    }
}
