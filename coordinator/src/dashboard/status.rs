//! The dashboard's one JSON document, `GET /api/status`: everything the page shows, read from the
//! run store (and, while the coordinator runs, from its queue). docs/reference/dashboard.md
//! documents each field; a field's meaning never changes, new ones may be added.

use serde::Serialize;

use crate::cluster::queue::{QueueStats, WorkerView};

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Status {
    pub run: RunInfo,
    pub progress: Progress,
    /// One row per island per recorded epoch: the rows of the run's `history.csv`.
    pub history: Vec<HistoryPoint>,
    /// The fittest design of the last recorded epoch.
    pub best: Option<Best>,
    pub islands: Vec<IslandRow>,
    /// The most recent migrations, newest first.
    pub migrations: Vec<Migration>,
    pub workers: Vec<WorkerRow>,
    /// The coordinator's task queue (only while it runs).
    pub queue: Option<Queue>,
    pub verification: Verification,
    /// Served by the running coordinator (true), or read from a store (false).
    pub live: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunInfo {
    pub name: String,
    /// The scene's `kind`: beam, locomotion, stiffness.
    pub task: String,
    /// The task's figure: its `history.csv` column, axis label and whether it reads on a log axis.
    pub figure: String,
    pub figure_axis: String,
    pub figure_log: bool,
    /// The paper's value of the figure, where it has one.
    pub paper_figure: Option<f64>,
    /// `budget.target_rms_percent`: the run stops once its best reaches it.
    pub target_figure: Option<f64>,
    pub budget_evaluations: Option<u64>,
    pub islands: usize,
    pub population: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Progress {
    /// Evaluations stored, the current epoch's finished ones included.
    pub evaluations: u64,
    /// Epochs recorded.
    pub epochs: u64,
    /// The run's wall time at its last recorded epoch, s.
    pub wall_seconds: f64,
    pub resolution: Option<String>,
    /// Over the last minute of evaluations.
    pub evaluations_per_second: Option<f64>,
    /// Until the evaluation budget is spent at that rate (a run that reaches its target stops
    /// sooner), s.
    pub seconds_left: Option<f64>,
}

/// A row of `history.csv`: an island after an epoch.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct HistoryPoint {
    pub epoch: u64,
    pub evaluations: u64,
    pub wall_seconds: f64,
    pub resolution: String,
    pub island: u32,
    pub best_fitness: Option<f64>,
    pub best_figure: Option<f64>,
    pub mean_fitness: Option<f64>,
    /// Children that replaced a parent in the epoch (`None` in a store too old to record it).
    pub replacements: Option<u64>,
    /// A multi-objective run's hypervolume of the island's population.
    pub hypervolume: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Best {
    /// Its evaluation: `GET /api/design.png?task=ID` draws it, `worker export --run DIR
    /// --design ID` exports it.
    pub task_id: u64,
    pub island: u32,
    pub evaluated_in_epoch: u64,
    pub resolution: String,
    pub worker: String,
    pub fitness: Option<f64>,
    pub figure: Option<f64>,
    /// The task's one-line figure (for a beam, its RMS error beside the paper's).
    pub headline: Option<String>,
    /// The task's summary of it (`summary.json`'s `best`): the paper's figures beside ours.
    pub summary: Option<serde_json::Value>,
    /// Its stored outcome: a beam's `profile` ([position, simulated, target] along the top
    /// surface), a robot's `centre_of_mass_trace`, and the other measurements.
    pub outcome: serde_json::Value,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IslandRow {
    pub island: u32,
    pub population: usize,
    pub best_fitness: Option<f64>,
    pub best_figure: Option<f64>,
    /// Individuals it has sent to other islands, and received.
    pub emigrants: u64,
    pub immigrants: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Migration {
    pub epoch: u64,
    pub from_island: u32,
    pub to_island: u32,
    pub task_id: u64,
}

/// A worker, from what the store recorded of it and, while the coordinator runs, from its queue.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorkerRow {
    /// `name @address (id)` as the queue names it (the store's `evaluation.worker`).
    pub label: String,
    pub evaluations: u64,
    /// Over the last minute.
    pub evaluations_per_second: f64,
    /// Outside workers' claims it checked.
    pub checks: u64,
    pub quarantined: bool,
    /// Registered now (live only): its threads, leases, principal.
    pub registered: Option<WorkerView>,
}

impl WorkerRow {
    pub(super) fn named(label: String) -> Self {
        Self {
            label,
            evaluations: 0,
            evaluations_per_second: 0.0,
            checks: 0,
            quarantined: false,
            registered: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Queue {
    pub workers: usize,
    pub queued: usize,
    pub leased: usize,
    pub expired_leases: u64,
    pub worker_errors: u64,
    pub duplicates: u64,
}

impl From<QueueStats> for Queue {
    fn from(s: QueueStats) -> Self {
        Self {
            workers: s.workers,
            queued: s.queued,
            leased: s.leased,
            expired_leases: s.expired_leases,
            worker_errors: s.worker_errors,
            duplicates: s.duplicates,
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Verification {
    /// Outside workers' claims checked by a second evaluation, and how many disagreed.
    pub checks: u64,
    pub disagreements: u64,
    pub quarantined_workers: u64,
    /// Claims stored but not yet checked.
    pub unchecked_claims: u64,
}

impl Status {
    /// Lays the queue's live view over what the store recorded: every registered worker is
    /// listed (one yet to finish an evaluation too), with its threads and leases.
    pub fn with_live(mut self, workers: Vec<WorkerView>, stats: QueueStats) -> Self {
        for view in workers {
            match self.workers.iter_mut().find(|w| w.label == view.label) {
                Some(row) => {
                    row.quarantined |= view.quarantined;
                    row.registered = Some(view);
                }
                None => {
                    let mut row = WorkerRow::named(view.label.clone());
                    row.quarantined = view.quarantined;
                    row.registered = Some(view);
                    self.workers.push(row);
                }
            }
        }
        self.queue = Some(stats.into());
        self.live = true;
        self
    }
}
