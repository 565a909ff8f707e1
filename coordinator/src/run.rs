//! The run loop: initial populations, epochs of breeding and evaluation, migration, resolution
//! switches, and the stopping rules.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use amorph::genome::Genome;
use amorph::outcome::Outcome;
use amorph::voxel::GridDims;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use tracing::info;

use crate::config::RunConfig;
use crate::evaluator::{Evaluator, EvaluatorError, Task};
use crate::ids::{IslandId, TaskId};
use crate::progress::Progress;
use crate::results::ResultWriter;
use crate::search::{Breeding, Individual, Island, ResolutionState, migrate};

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Evaluator(#[from] EvaluatorError),
    #[error("results: {0}")]
    Results(#[from] std::io::Error),
}

pub type Result<T> = std::result::Result<T, RunError>;

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    EvaluationBudget,
    WallTime,
    TargetReached,
    Shutdown,
}

/// One line of the fitness history: an island after an epoch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HistoryRow {
    pub epoch: usize,
    pub evaluations: u64,
    pub wall_seconds: f64,
    pub resolution: String,
    pub island: u32,
    pub best_fitness: Option<f64>,
    pub best_rms_percent: Option<f64>,
    pub mean_fitness: Option<f64>,
    pub replacements: usize,
}

/// What a finished run hands back (and writes to its results folder).
#[derive(Debug)]
pub struct RunSummary {
    pub stop: StopReason,
    pub epochs: usize,
    pub evaluations: u64,
    pub wall_seconds: f64,
    pub dims: GridDims,
    /// Every island's final population, in slot order.
    pub populations: Vec<Vec<Individual>>,
    pub history: Vec<HistoryRow>,
}

impl RunSummary {
    /// The fittest individual of the run (the lowest island, then slot, on a tie).
    pub fn best(&self) -> &Individual {
        let mut best = &self.populations[0][0];
        for ind in self.populations.iter().flatten() {
            if ind.outcome.is_fitter_than(&best.outcome) {
                best = ind;
            }
        }
        best
    }
}

/// The state of a search between epochs.
struct Search {
    islands: Vec<Island>,
    migration_rng: ChaCha8Rng,
    resolution: ResolutionState,
    epoch: usize,
    evaluations: u64,
    next_task: u64,
}

/// Runs a whole search with the given evaluator. Results are written as the run goes (history per
/// epoch, best design when it improves) so an interrupted run keeps what it finished.
pub fn run(
    config: &RunConfig,
    evaluator: &mut dyn Evaluator,
    shutdown: &AtomicBool,
    progress: &Progress,
) -> Result<RunSummary> {
    let raw = &config.raw;
    let started = Instant::now();
    let scene = Arc::new(raw.scene.clone());
    let breeding = Breeding {
        mutation: raw.search.mutation.clone(),
        limits: scene.limits().clone(),
        material_count: scene.palette().len(),
    };
    let schedule = &raw.resolution;
    let mut writer = ResultWriter::create(config)?;
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
    let mut search = Search {
        islands: Vec::new(),
        migration_rng,
        resolution: ResolutionState::new(),
        epoch: 0,
        evaluations: 0,
        next_task: 0,
    };
    let dims = schedule.dims(0);
    let outcomes = evaluate_all(&mut search, evaluator, &initial, dims, progress)?;
    search.islands = initial
        .into_iter()
        .zip(outcomes)
        .zip(rngs)
        .enumerate()
        .map(|(i, ((genomes, outcomes), rng))| {
            let population = genomes
                .into_iter()
                .zip(outcomes)
                .map(|(genome, outcome)| Individual { genome, outcome })
                .collect();
            Island::from_evaluated(IslandId(i as u32), rng, population)
        })
        .collect();

    let budget = &raw.budget;
    let stop = loop {
        let dims = schedule.dims(search.resolution.level);
        if let Some(reason) = stop_reason(config, &search, started, shutdown) {
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
                island.breed(count, &breeding)
            })
            .collect();
        let genomes: Vec<Vec<Genome>> = children
            .iter()
            .map(|c| c.iter().map(|c| c.genome.clone()).collect())
            .collect();
        let outcomes = evaluate_all(&mut search, evaluator, &genomes, dims, progress)?;
        search.epoch += 1;
        let wall = started.elapsed().as_secs_f64();
        for ((island, children), outcomes) in search.islands.iter_mut().zip(children).zip(outcomes)
        {
            let replacements = island.apply(children, outcomes);
            let row = history_row(
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
        if migration.interval > 0 && search.epoch.is_multiple_of(migration.interval) {
            for event in migrate(&mut search.islands, migration, &mut search.migration_rng) {
                info!(from = %event.from, to = %event.to, replaced = ?event.replaced, "migration");
            }
        }

        let best = best_of(&search.islands);
        writer.best_so_far(best, dims)?;
        progress.epoch(search.epoch, best.outcome.headline(), dims);

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
            let outcomes = evaluate_all(&mut search, evaluator, &genomes, dims, progress)?;
            for (island, outcomes) in search.islands.iter_mut().zip(outcomes) {
                for (ind, outcome) in island.population.iter_mut().zip(outcomes) {
                    ind.outcome = outcome;
                }
            }
        }
    };

    let dims = schedule.dims(search.resolution.level);
    let summary = RunSummary {
        stop,
        epochs: search.epoch,
        evaluations: search.evaluations,
        wall_seconds: started.elapsed().as_secs_f64(),
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
    search: &Search,
    started: Instant,
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
    if budget
        .wall_seconds
        .is_some_and(|max| started.elapsed().as_secs_f64() >= max)
    {
        return Some(StopReason::WallTime);
    }
    let best_rms = best_of(&search.islands)
        .outcome
        .beam_metrics()
        .map(|m| m.rms_percent);
    if let (Some(target), Some(rms)) = (budget.target_rms_percent, best_rms)
        && search.resolution.is_final(&config.raw.resolution)
        && rms <= target
    {
        return Some(StopReason::TargetReached);
    }
    None
}

/// Evaluates one batch of genomes per island as a single evaluator call, returning the outcomes
/// grouped the same way.
fn evaluate_all(
    search: &mut Search,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    progress: &Progress,
) -> Result<Vec<Vec<Outcome>>> {
    let tasks: Vec<Task> = genomes
        .iter()
        .flatten()
        .map(|genome| {
            search.next_task += 1;
            Task {
                id: TaskId(search.next_task),
                genome: genome.clone(),
                dims,
            }
        })
        .collect();
    let mut outcomes = evaluator
        .evaluate(&tasks, &|_| progress.evaluated())?
        .into_iter();
    search.evaluations += tasks.len() as u64;
    Ok(genomes
        .iter()
        .map(|g| outcomes.by_ref().take(g.len()).collect())
        .collect())
}

fn best_of(islands: &[Island]) -> &Individual {
    let mut best = islands[0].best();
    for island in &islands[1..] {
        if island.best().outcome.is_fitter_than(&best.outcome) {
            best = island.best();
        }
    }
    best
}

fn history_row(
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
        best_rms_percent: best.outcome.beam_metrics().map(|m| m.rms_percent),
        mean_fitness: (!valid.is_empty()).then(|| valid.iter().sum::<f64>() / valid.len() as f64),
        replacements,
    }
}
