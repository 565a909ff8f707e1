//! What a run writes to its store as it goes: evaluations, checks of outside claims, task errors
//! and the end of each epoch.

use amorph::genome::Genome;
use amorph::task::Outcome;
use rusqlite::params;

use super::{Result, RunStore, unix_now};
use crate::ids::TaskId;
use crate::summary::HistoryRow;

/// Why a task was evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    Initial,
    Child,
    Reevaluation,
    /// The run's best at a coarse level, evaluated at the finest (`resolution.stall_on_finest`).
    FinestCheck,
    /// A genome a caller outside the search asked for (`AskedRun`: an optimizer of its own).
    Asked,
}

impl Purpose {
    const ALL: [Self; 5] = [
        Self::Initial,
        Self::Child,
        Self::Reevaluation,
        Self::FinestCheck,
        Self::Asked,
    ];

    /// The purpose a store names `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.as_str() == name)
    }

    fn as_str(self) -> &'static str {
        match self {
            Self::Initial => "initial",
            Self::Child => "child",
            Self::Reevaluation => "reevaluation",
            Self::FinestCheck => "finest_check",
            Self::Asked => "asked",
        }
    }
}

/// One evaluation as the store records it.
#[derive(Clone, Debug)]
pub struct EvaluationRecord<'a> {
    pub task_id: TaskId,
    pub epoch: usize,
    pub island: u32,
    pub purpose: Purpose,
    pub resolution: String,
    pub genome: &'a Genome,
    pub outcome: &'a Outcome,
    pub worker: &'a str,
    pub wall_seconds: f64,
    /// When the evaluation finished, s since the Unix epoch (a held one is stored later).
    pub finished_unix: f64,
    /// An outside worker's claim, not yet checked.
    pub unchecked: bool,
}

/// A stored outcome, to be reused by a resumed run if its task draws the same genome again.
#[derive(Clone, Debug)]
pub struct StoredEvaluation {
    pub genome_json: String,
    pub resolution: String,
    pub outcome: Outcome,
    /// An outside worker's claim that was never checked: the resumed run checks it if it decides.
    pub unchecked: bool,
}

/// The end of an epoch as [`RunStore::record_epoch`] stores it.
#[derive(Debug)]
pub struct EpochRecord<'a> {
    pub epoch: usize,
    pub evaluations: u64,
    pub wall_seconds: f64,
    pub resolution: String,
    pub best_fitness: Option<f64>,
    /// Per island, per slot: (task id of the individual's evaluation, its fitness).
    pub populations: Vec<Vec<(TaskId, Option<f64>)>>,
    pub migrations: &'a [MigrationRecord],
    /// Each island's `history.csv` row for the epoch.
    pub history: &'a [HistoryRow],
}

#[derive(Clone, Debug, PartialEq)]
pub struct MigrationRecord {
    pub from: u32,
    pub to: u32,
    pub emigrant_slot: usize,
    pub replaced_slot: Option<usize>,
    pub task_id: TaskId,
}

impl RunStore {
    pub fn record_evaluation(&self, r: &EvaluationRecord<'_>) -> Result<()> {
        let genome = serde_json::to_string(r.genome).expect("genomes serialize");
        let outcome = serde_json::to_string(r.outcome).expect("outcomes serialize");
        let finished = r.finished_unix;
        self.with(|c| {
            let tx = c.transaction()?;
            tx.prepare_cached(
                "INSERT OR REPLACE INTO evaluation(task_id, epoch, island, purpose, resolution, genome, outcome, fitness, worker, wall_seconds, finished_unix)
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)",
            )?
            .execute(params![
                r.task_id.0 as i64,
                r.epoch as i64,
                r.island,
                r.purpose.as_str(),
                r.resolution,
                genome,
                outcome,
                r.outcome.fitness(),
                r.worker,
                r.wall_seconds,
                finished
            ])?;
            if r.unchecked {
                tx.execute(
                    "INSERT OR REPLACE INTO unchecked(task_id) VALUES (?1)",
                    [r.task_id.0 as i64],
                )?;
            }
            tx.commit()
        })
    }

    /// Records a check of the claim for `task_id`: the verdict, the outcome that holds in place of
    /// a contradicted claim, and the quarantine of every worker caught disagreeing.
    pub fn record_check(
        &self,
        task_id: TaskId,
        claimant: &str,
        claimed: &Outcome,
        verdict: &crate::evaluator::Verdict,
    ) -> Result<()> {
        let (task_id, finished) = (task_id.0, unix_now());
        let claimed = serde_json::to_string(claimed).expect("outcomes serialize");
        let held = serde_json::to_string(&verdict.outcome).expect("outcomes serialize");
        self.with(|c| {
            let tx = c.transaction()?;
            tx.execute(
                "INSERT INTO verification(task_id, claimant, checker, agreed, claimed, finished_unix) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                params![task_id as i64, claimant, verdict.checker, verdict.agreed, claimed, finished],
            )?;
            if !verdict.agreed {
                tx.execute(
                    "UPDATE evaluation SET outcome = ?2, fitness = ?3, worker = ?4 WHERE task_id = ?1",
                    params![task_id as i64, held, verdict.outcome.fitness(), verdict.checker],
                )?;
            }
            for liar in &verdict.liars {
                tx.execute(
                    "INSERT INTO quarantine(worker, task_id, finished_unix) VALUES (?1, ?2, ?3)",
                    params![liar.to_string(), task_id as i64, finished],
                )?;
            }
            tx.execute("DELETE FROM unchecked WHERE task_id = ?1", [task_id as i64])?;
            tx.commit()
        })
    }

    pub fn record_task_error(&self, task_id: TaskId, worker: &str, message: &str) -> Result<()> {
        let task_id = task_id.0;
        self.with(|c| {
            c.execute(
                "INSERT INTO task_error(task_id, worker, message) VALUES (?1, ?2, ?3)",
                params![task_id as i64, worker, message],
            )?;
            Ok(())
        })
    }

    /// Records the end of an epoch: its totals, every island's population (slot → task id) and the
    /// epoch's migrations, in one transaction.
    pub fn record_epoch(&self, epoch: &EpochRecord<'_>) -> Result<()> {
        self.with(|c| {
            let tx = c.transaction()?;
            tx.execute(
                "INSERT OR REPLACE INTO epoch(epoch, evaluations, wall_seconds, resolution, best_fitness) VALUES (?1, ?2, ?3, ?4, ?5)",
                params![
                    epoch.epoch as i64,
                    epoch.evaluations as i64,
                    epoch.wall_seconds,
                    epoch.resolution,
                    epoch.best_fitness
                ],
            )?;
            {
                let mut row = tx.prepare_cached(
                    "INSERT OR REPLACE INTO population(epoch, island, slot, task_id, fitness) VALUES (?1, ?2, ?3, ?4, ?5)",
                )?;
                for (island, members) in epoch.populations.iter().enumerate() {
                    for (slot, &(task, fitness)) in members.iter().enumerate() {
                        row.execute(params![
                            epoch.epoch as i64,
                            island as i64,
                            slot as i64,
                            task.0 as i64,
                            fitness
                        ])?;
                    }
                }
                tx.execute(
                    "DELETE FROM migration WHERE epoch = ?1",
                    [epoch.epoch as i64],
                )?;
                let mut row = tx.prepare_cached(
                    "INSERT INTO migration(epoch, from_island, to_island, emigrant_slot, replaced_slot, task_id) VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                )?;
                for m in epoch.migrations {
                    row.execute(params![
                        epoch.epoch as i64,
                        m.from,
                        m.to,
                        m.emigrant_slot as i64,
                        m.replaced_slot.map(|s| s as i64),
                        m.task_id.0 as i64
                    ])?;
                }
                let mut row = tx.prepare_cached(
                    "INSERT OR REPLACE INTO history(epoch, island, best_fitness, best_figure, mean_fitness, replacements, hypervolume) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
                )?;
                for h in epoch.history {
                    row.execute(params![
                        epoch.epoch as i64,
                        h.island,
                        h.best_fitness,
                        h.best_figure,
                        h.mean_fitness,
                        h.replacements as i64,
                        h.hypervolume
                    ])?;
                }
            }
            tx.commit()
        })
    }
}
