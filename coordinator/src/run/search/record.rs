//! What an epoch leaves behind: its lines of `history.csv` and its record in the run store,
//! checked against the earlier session's record while a resumed run replays.

use amorph::task::Scene;
use amorph::voxel::GridDims;

use super::super::{Result, RunError};
use super::Search;
use crate::ids::TaskId;
use crate::search::Island;
use crate::store::{EpochRecord, MigrationRecord, RunStore};
use crate::summary::HistoryRow;

impl Search {
    /// Each island's line of `history.csv` for the epoch just applied.
    pub(in crate::run) fn history_rows(
        &self,
        scene: &Scene,
        dims: GridDims,
        replacements: &[usize],
    ) -> Vec<HistoryRow> {
        let wall = self.clock.seconds();
        self.islands
            .iter()
            .zip(replacements)
            .map(|(island, &replacements)| {
                history_row(
                    scene,
                    island,
                    self.ledger.epoch,
                    self.ledger.evaluations,
                    wall,
                    dims,
                    replacements,
                )
            })
            .collect()
    }
}

/// Stores the end of an epoch. While replaying, first checks the replayed populations against the
/// ones the earlier session recorded: any difference means the store is not this run's.
pub(in crate::run) fn record_epoch(
    search: &Search,
    migrations: &[MigrationRecord],
    history: &[HistoryRow],
    dims: GridDims,
    store: &RunStore,
) -> Result<()> {
    let populations: Vec<Vec<(TaskId, Option<f64>)>> = search
        .islands
        .iter()
        .map(|i| {
            i.population
                .iter()
                .map(|ind| (ind.task, ind.outcome.fitness()))
                .collect()
        })
        .collect();
    if search
        .replay_until
        .is_some_and(|last| search.ledger.epoch <= last)
    {
        let stored = store.population(search.ledger.epoch)?;
        let replayed: Vec<Vec<TaskId>> = populations
            .iter()
            .map(|p| p.iter().map(|&(t, _)| t).collect())
            .collect();
        if stored != replayed {
            return Err(RunError::Replay(format!(
                "the replayed populations of epoch {} differ from the ones {} recorded",
                search.ledger.epoch,
                store.path().display()
            )));
        }
    }
    store.record_epoch(&EpochRecord {
        epoch: search.ledger.epoch,
        evaluations: search.ledger.evaluations,
        // The epoch's one wall time: the one its history rows carry.
        wall_seconds: (history.first()).map_or_else(|| search.clock.seconds(), |h| h.wall_seconds),
        resolution: dims.to_string(),
        best_fitness: search.best().outcome.fitness(),
        populations,
        migrations,
        history,
    })?;
    Ok(())
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
        hypervolume: island.hypervolume(),
    }
}
