//! The run store: one SQLite file per run (`<results>/<name>/run.sqlite`) holding the config, every
//! evaluation, a population snapshot per epoch and every migration, written as the run goes.
//!
//! Resuming replays the search from the seed: breeding is cheap and deterministic, so the replay
//! draws the very same genomes and task ids, and every task already in the store takes its stored
//! outcome instead of being evaluated again. The resumed run therefore ends bit-identical to an
//! uninterrupted one, and nothing a worker finished before the crash is evaluated twice.
//!
//! Tables (analyse them with any SQLite tool, also while the run goes on: the file is in WAL mode):
//! - `run(key, value)`: `config` (the effective config as TOML), `format`.
//! - `evaluation(task_id, epoch, island, purpose, resolution, genome, outcome, fitness, worker,
//!   wall_seconds, finished_unix)`: genome and outcome as the shared library's JSON.
//! - `epoch(epoch, evaluations, wall_seconds, resolution, best_fitness)`.
//! - `population(epoch, island, slot, task_id, fitness)`: who held each slot after the epoch (the
//!   genome is the evaluation's, by task id, so snapshots cost a few bytes per individual).
//! - `migration(epoch, from_island, to_island, emigrant_slot, replaced_slot, task_id)`.
//! - `task_error(task_id, worker, message)`: a worker's error for a task, noted before a retry.
//! - `unchecked(task_id)`: evaluations that are an outside worker's claim not yet checked (a resumed
//!   run checks them before they count; see `verification.rs`).
//! - `verification(task_id, claimant, checker, agreed, claimed, finished_unix)`: each check of a
//!   claim; where it disagreed, `claimed` keeps the claim and the evaluation row holds the outcome
//!   that held.
//! - `quarantine(worker, task_id, finished_unix)`: a worker caught disagreeing, and on which task.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use amorph::genome::Genome;
use amorph::task::Outcome;
use rusqlite::{Connection, OptionalExtension, params};

use crate::config::RunConfig;
use crate::ids::TaskId;
use crate::run::schedule::RecordedRun;

const FORMAT: &str = "amorph-run-store-1";

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("run store {path}: {source}")]
    Sqlite {
        path: PathBuf,
        source: rusqlite::Error,
    },
    #[error(
        "run store {0} already exists: pass --resume to continue that run, or --fresh to delete it and start over"
    )]
    Exists(PathBuf),
    #[error("run store {0} does not exist: nothing to resume (run without --resume)")]
    Missing(PathBuf),
    #[error(
        "run store {path} was made by a different config ({differs} differs); only [budget], [cluster] and results_dir may change on --resume"
    )]
    ConfigChanged { path: PathBuf, differs: String },
    #[error("run store {path}: {message}")]
    Corrupt { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, StoreError>;

/// Why a task was evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Purpose {
    Initial,
    Child,
    Reevaluation,
    /// The run's best at a coarse level, evaluated at the finest (`resolution.stall_on_finest`).
    FinestCheck,
}

impl Purpose {
    const ALL: [Self; 4] = [
        Self::Initial,
        Self::Child,
        Self::Reevaluation,
        Self::FinestCheck,
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

#[derive(Debug)]
pub struct RunStore {
    path: PathBuf,
    conn: Mutex<Connection>,
}

impl RunStore {
    pub fn path_for(config: &RunConfig) -> PathBuf {
        config.run_dir().join("run.sqlite")
    }

    /// Creates the store of a new run. An existing store is an error unless `fresh` (then it is
    /// deleted), so a finished run is never overwritten by accident.
    pub fn create(config: &RunConfig, fresh: bool) -> Result<Self> {
        let path = Self::path_for(config);
        if path.exists() {
            if !fresh {
                return Err(StoreError::Exists(path));
            }
            for suffix in ["", "-wal", "-shm"] {
                let mut p = path.clone().into_os_string();
                p.push(suffix);
                let _ = std::fs::remove_file(PathBuf::from(p));
            }
        }
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| StoreError::Corrupt {
                path: path.clone(),
                message: format!("cannot create its folder: {e}"),
            })?;
        }
        let store = Self::open_file(&path)?;
        store.with(|c| {
            c.execute_batch(SCHEMA)?;
            c.execute(
                "INSERT INTO run(key, value) VALUES ('format', ?1), ('config', ?2)",
                params![FORMAT, config_text(config)],
            )?;
            Ok(())
        })?;
        Ok(store)
    }

    /// Opens the store of an earlier run of this config to resume it. The config must be the one
    /// the store was made with, except for `[budget]` (a run may be extended).
    pub fn resume(config: &RunConfig) -> Result<Self> {
        let path = Self::path_for(config);
        if !path.exists() {
            return Err(StoreError::Missing(path));
        }
        let store = Self::open_file(&path)?;
        let stored: Option<(String, String)> = store.with(|c| {
            let get = |key: &str| {
                c.query_row("SELECT value FROM run WHERE key = ?1", [key], |r| r.get(0))
                    .optional()
            };
            Ok(match (get("format")?, get("config")?) {
                (Some(f), Some(cfg)) => Some((f, cfg)),
                _ => None,
            })
        })?;
        let Some((format, stored_config)) = stored else {
            return Err(StoreError::Corrupt {
                path,
                message: "no format or config recorded".into(),
            });
        };
        if format != FORMAT {
            return Err(StoreError::Corrupt {
                path,
                message: format!("format {format:?}, this coordinator reads {FORMAT:?}"),
            });
        }
        // Read the stored config with today's schema first, so that a key added since (with the
        // default that reproduces the old behaviour, e.g. `scene.dynamics.poisson`) does not
        // count as a change; one that no longer parses is compared as stored, and so differs.
        let stored_config = RunConfig::parse(&stored_config, &path)
            .map(|c| config_text(&c))
            .unwrap_or(stored_config);
        let stored: toml::Table =
            toml::from_str(&stored_config).map_err(|e| StoreError::Corrupt {
                path: path.clone(),
                message: format!("stored config: {}", e.message()),
            })?;
        let current: toml::Table =
            toml::from_str(&config_text(config)).expect("our own TOML parses");
        if let Some(differs) = first_difference(&stored, &current) {
            return Err(StoreError::ConfigChanged { path, differs });
        }
        store.with(|c| {
            c.execute(
                "UPDATE run SET value = ?1 WHERE key = 'config'",
                [config_text(config)],
            )?;
            Ok(())
        })?;
        Ok(store)
    }

    fn open_file(path: &Path) -> Result<Self> {
        let conn = Connection::open(path).map_err(|source| StoreError::Sqlite {
            path: path.to_owned(),
            source,
        })?;
        let store = Self {
            path: path.to_owned(),
            conn: Mutex::new(conn),
        };
        // WAL: readers (a user's sqlite3 shell) never block the run; NORMAL sync keeps every
        // committed row across a crash of this process (not across a power cut, which is the
        // price of not syncing each evaluation to disk). The verification tables are created on
        // open, so a store written before they existed resumes with them empty.
        store.with(|c| {
            c.pragma_update(None, "journal_mode", "WAL")?;
            c.pragma_update(None, "synchronous", "NORMAL")?;
            c.busy_timeout(std::time::Duration::from_secs(10))?;
            c.execute_batch(VERIFICATION_SCHEMA)?;
            Ok(())
        })?;
        Ok(store)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    fn with<T>(&self, f: impl FnOnce(&mut Connection) -> rusqlite::Result<T>) -> Result<T> {
        let mut conn = self.conn.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut conn).map_err(|source| StoreError::Sqlite {
            path: self.path.clone(),
            source,
        })
    }

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

    /// Checks a store holds, read without opening it for writing (a run may be going on):
    /// (checks, checks that disagreed, distinct workers quarantined).
    pub fn peek_verification(path: &Path) -> Result<(u64, u64, u64)> {
        peek(path, |conn| {
            conn.query_row(
                "SELECT (SELECT count(*) FROM verification), (SELECT count(*) FROM verification WHERE NOT agreed), (SELECT count(DISTINCT worker) FROM quarantine)",
                [],
                |r| {
                    Ok((
                        r.get::<_, i64>(0)? as u64,
                        r.get::<_, i64>(1)? as u64,
                        r.get::<_, i64>(2)? as u64,
                    ))
                },
            )
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
            }
            tx.commit()
        })
    }

    /// Every stored evaluation by task id, for a resumed run's replay.
    pub fn evaluations(&self) -> Result<HashMap<TaskId, StoredEvaluation>> {
        let rows: Vec<(i64, String, String, String, bool)> = self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT task_id, genome, resolution, outcome, task_id IN (SELECT task_id FROM unchecked) FROM evaluation",
            )?;
            let rows = stmt
                .query_map([], |r| {
                    Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?, r.get(4)?))
                })?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        rows.into_iter()
            .map(|(id, genome_json, resolution, outcome, unchecked)| {
                let id = u64::try_from(id).map_err(|_| StoreError::Corrupt {
                    path: self.path.clone(),
                    message: format!("table evaluation, row task_id {id}: negative task id"),
                })?;
                let outcome = serde_json::from_str(&outcome).map_err(|e| StoreError::Corrupt {
                    path: self.path.clone(),
                    message: format!("evaluation of task {id}: {e}"),
                })?;
                Ok((
                    TaskId(id),
                    StoredEvaluation {
                        genome_json,
                        resolution,
                        outcome,
                        unchecked,
                    },
                ))
            })
            .collect()
    }

    /// Wall seconds the run had used at its last recorded epoch (0 for a new run).
    pub fn recorded_wall_seconds(&self) -> Result<f64> {
        self.with(|c| {
            c.query_row(
                "SELECT COALESCE(MAX(wall_seconds), 0.0) FROM epoch",
                [],
                |r| r.get(0),
            )
        })
    }

    /// The run's evaluation count at the end of every recorded epoch, by epoch (empty before the
    /// first epoch ended; the last recorded epoch is its largest key).
    pub fn epoch_evaluations(&self) -> Result<HashMap<usize, u64>> {
        let rows: Vec<(i64, i64)> = self.with(|c| {
            let mut stmt = c.prepare("SELECT epoch, evaluations FROM epoch")?;
            let rows = stmt
                .query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        rows.into_iter()
            .map(
                |(epoch, n)| match (usize::try_from(epoch), u64::try_from(n)) {
                    (Ok(epoch), Ok(n)) => Ok((epoch, n)),
                    _ => Err(StoreError::Corrupt {
                        path: self.path.clone(),
                        message: format!("table epoch, row epoch {epoch}: evaluations {n}"),
                    }),
                },
            )
            .collect()
    }

    /// The population of every island after `epoch`, as task ids in slot order.
    pub fn population(&self, epoch: usize) -> Result<Vec<Vec<TaskId>>> {
        let rows: Vec<(i64, i64, i64)> = self.with(|c| {
            let mut stmt = c.prepare(
                "SELECT island, slot, task_id FROM population WHERE epoch = ?1 ORDER BY island, slot",
            )?;
            let rows = stmt
                .query_map([epoch as i64], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            Ok(rows)
        })?;
        let mut islands: Vec<Vec<TaskId>> = Vec::new();
        for (island, slot, task) in rows {
            // A store is a file anyone may have edited: a row that cannot be a population entry
            // is an error naming it, never an index out of range or a huge allocation.
            let corrupt = |what: &str| StoreError::Corrupt {
                path: self.path.clone(),
                message: format!(
                    "table population, row (epoch {epoch}, island {island}, slot {slot}, task_id {task}): {what}"
                ),
            };
            let i = usize::try_from(island)
                .ok()
                .filter(|&i| i <= islands.len())
                .ok_or_else(|| corrupt("island out of order or out of range"))?;
            let task = u64::try_from(task).map_err(|_| corrupt("negative task id"))?;
            if i == islands.len() {
                islands.push(Vec::new());
            }
            islands[i].push(TaskId(task));
        }
        Ok(islands)
    }

    /// What the wall-time model needs from the store at `path` (read-only): every recorded epoch,
    /// every evaluation's epoch, purpose and time, how many distinct workers evaluated, and
    /// whether the run overlapped its finest-level checks (stores from before that key did not).
    pub fn peek_recorded_run(path: &Path) -> Result<RecordedRun> {
        let (epochs, evaluations, workers, config) = peek(path, |conn| {
            let mut stmt = conn.prepare(
                "SELECT epoch, evaluations, wall_seconds, best_fitness FROM epoch ORDER BY epoch",
            )?;
            let epochs = stmt
                .query_map([], |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, i64>(1)?,
                        r.get::<_, f64>(2)?,
                        r.get::<_, Option<f64>>(3)?,
                    ))
                })?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            let mut stmt = conn.prepare(
                "SELECT task_id, epoch, purpose, wall_seconds FROM evaluation ORDER BY task_id",
            )?;
            let evaluations = stmt
                .query_map([], |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, i64>(1)?,
                        r.get::<_, String>(2)?,
                        r.get::<_, f64>(3)?,
                    ))
                })?
                .collect::<rusqlite::Result<Vec<_>>>()?;
            let workers: i64 =
                conn.query_row("SELECT COUNT(DISTINCT worker) FROM evaluation", [], |r| {
                    r.get(0)
                })?;
            let config: Option<String> = conn
                .query_row("SELECT value FROM run WHERE key = 'config'", [], |r| {
                    r.get(0)
                })
                .optional()?;
            Ok((epochs, evaluations, workers, config))
        })?;
        let corrupt = |message: String| StoreError::Corrupt {
            path: path.to_owned(),
            message,
        };
        let mut rows = Vec::with_capacity(epochs.len());
        for (epoch, evaluations, wall_seconds, best_fitness) in epochs {
            let (Ok(epoch), Ok(count)) = (usize::try_from(epoch), u64::try_from(evaluations))
            else {
                return Err(corrupt(format!(
                    "table epoch, row epoch {epoch}: negative epoch or evaluation count"
                )));
            };
            rows.push((epoch, count, wall_seconds, best_fitness));
        }
        let mut timed = Vec::with_capacity(evaluations.len());
        for (task, epoch, purpose, wall) in evaluations {
            let at = |what: String| corrupt(format!("table evaluation, task {task}: {what}"));
            let epoch = usize::try_from(epoch).map_err(|_| at(format!("epoch {epoch}")))?;
            let purpose =
                Purpose::parse(&purpose).ok_or_else(|| at(format!("purpose {purpose:?}")))?;
            if !(wall.is_finite() && wall >= 0.0) {
                return Err(at(format!("wall_seconds {wall}")));
            }
            timed.push((epoch, purpose, wall));
        }
        let overlapped = config
            .and_then(|text| text.parse::<toml::Table>().ok())
            .and_then(|t| t.get("resolution")?.get("overlap_finest_checks")?.as_bool())
            .unwrap_or(false);
        Ok(RecordedRun {
            rows,
            evaluations: timed,
            workers: usize::try_from(workers).unwrap_or(0),
            overlapped,
        })
    }

    /// Evaluations in the store at `path`, read without disturbing a run that is writing it (the
    /// way to watch a run from outside).
    pub fn peek_evaluation_count(path: &Path) -> Result<u64> {
        peek(path, |conn| {
            conn.query_row("SELECT COUNT(*) FROM evaluation", [], |r| {
                r.get::<_, i64>(0)
            })
            .map(|n| n as u64)
        })
    }

    /// Number of evaluations stored.
    pub fn evaluation_count(&self) -> Result<u64> {
        self.with(|c| {
            c.query_row("SELECT COUNT(*) FROM evaluation", [], |r| {
                r.get::<_, i64>(0)
            })
        })
        .map(|n| n as u64)
    }
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
}

#[derive(Clone, Debug, PartialEq)]
pub struct MigrationRecord {
    pub from: u32,
    pub to: u32,
    pub emigrant_slot: usize,
    pub replaced_slot: Option<usize>,
    pub task_id: TaskId,
}

const SCHEMA: &str = "
CREATE TABLE run (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE evaluation (
    task_id INTEGER PRIMARY KEY,
    epoch INTEGER NOT NULL,
    island INTEGER NOT NULL,
    purpose TEXT NOT NULL,
    resolution TEXT NOT NULL,
    genome TEXT NOT NULL,
    outcome TEXT NOT NULL,
    fitness REAL,
    worker TEXT NOT NULL,
    wall_seconds REAL NOT NULL,
    finished_unix REAL NOT NULL
);
CREATE TABLE epoch (
    epoch INTEGER PRIMARY KEY,
    evaluations INTEGER NOT NULL,
    wall_seconds REAL NOT NULL,
    resolution TEXT NOT NULL,
    best_fitness REAL
);
CREATE TABLE population (
    epoch INTEGER NOT NULL,
    island INTEGER NOT NULL,
    slot INTEGER NOT NULL,
    task_id INTEGER NOT NULL,
    fitness REAL,
    PRIMARY KEY (epoch, island, slot)
);
CREATE TABLE migration (
    epoch INTEGER NOT NULL,
    from_island INTEGER NOT NULL,
    to_island INTEGER NOT NULL,
    emigrant_slot INTEGER NOT NULL,
    replaced_slot INTEGER,
    task_id INTEGER NOT NULL
);
CREATE INDEX migration_epoch ON migration(epoch);
CREATE TABLE task_error (task_id INTEGER NOT NULL, worker TEXT NOT NULL, message TEXT NOT NULL);
";

const VERIFICATION_SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS unchecked (task_id INTEGER PRIMARY KEY);
CREATE TABLE IF NOT EXISTS verification (
    task_id INTEGER NOT NULL,
    claimant TEXT NOT NULL,
    checker TEXT NOT NULL,
    agreed INTEGER NOT NULL,
    claimed TEXT NOT NULL,
    finished_unix REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS quarantine (worker TEXT NOT NULL, task_id INTEGER NOT NULL, finished_unix REAL NOT NULL);
";

/// Runs `query` on the store at `path` opened read-only, so a run writing it is not disturbed.
fn peek<T>(path: &Path, query: impl FnOnce(&Connection) -> rusqlite::Result<T>) -> Result<T> {
    let sqlite = |source| StoreError::Sqlite {
        path: path.to_owned(),
        source,
    };
    let conn = Connection::open_with_flags(path, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
        .map_err(sqlite)?;
    conn.busy_timeout(std::time::Duration::from_secs(5))
        .map_err(sqlite)?;
    query(&conn).map_err(sqlite)
}

pub(crate) fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

fn config_text(config: &RunConfig) -> String {
    toml::to_string(&config.raw).expect("configs serialize")
}

/// The first key (dotted) whose value differs between two configs, ignoring `budget` (a run may
/// be extended), `cluster` (how workers connect never changes a result) and `results_dir` (a
/// stopped run's folder may be moved, e.g. from a lent machine to the one that finishes it: the
/// store is found through the new path, so nothing of the old one is read).
fn first_difference(a: &toml::Table, b: &toml::Table) -> Option<String> {
    first_difference_except(a, b, &["budget", "cluster", "results_dir"])
}

/// The first key (dotted, in sorted order) whose value differs, skipping top-level `ignored` keys.
fn first_difference_except(a: &toml::Table, b: &toml::Table, ignored: &[&str]) -> Option<String> {
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .filter(|key| !ignored.contains(&key.as_str()))
        .find_map(|key| match (a.get(key), b.get(key)) {
            (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                first_difference_except(x, y, &[]).map(|inner| format!("{key}.{inner}"))
            }
            (x, y) if x != y => Some(key.clone()),
            _ => None,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn locomotion_config(dir: &Path, seed: u64) -> RunConfig {
        let text = format!(
            "name = \"resume-schema\"\nseed = {seed}\nresults_dir = {:?}\n\n[budget]\nevaluations = 100\n\n\
             [resolution]\nlevels = [[4, 4, 4]]\n\n[scene]\nkind = \"locomotion\"\n",
            dir.display().to_string()
        );
        RunConfig::parse(&text, Path::new("resume-schema.toml")).expect("valid config")
    }

    /// A store written before a key existed (here `scene.dynamics.poisson`, whose default is the
    /// old behaviour) resumes; a real change still does not.
    #[test]
    fn resume_reads_the_stored_config_with_todays_defaults() {
        let dir = std::env::temp_dir().join(format!("amorph-store-{}", std::process::id()));
        let config = locomotion_config(&dir, 1);
        let store = RunStore::create(&config, true).unwrap();
        let old_text: String = config_text(&config)
            .lines()
            .filter(|line| !line.starts_with("poisson ="))
            .map(|line| format!("{line}\n"))
            .collect();
        assert_ne!(
            old_text,
            config_text(&config),
            "the key must be in today's config"
        );
        store
            .with(|c| {
                c.execute(
                    "UPDATE run SET value = ?1 WHERE key = 'config'",
                    [&old_text],
                )?;
                Ok(())
            })
            .unwrap();
        drop(store);
        RunStore::resume(&config).expect("an added key with its old default resumes");
        match RunStore::resume(&locomotion_config(&dir, 2)) {
            Err(StoreError::ConfigChanged { differs, .. }) => assert_eq!(differs, "seed"),
            other => panic!("a changed seed must not resume: {:?}", other.map(|_| ())),
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Issue 12, item 8: a store edited to hold a negative island panicked; a corrupt row is an
    /// error naming the table and the row.
    #[test]
    fn regression_a_corrupt_population_row_is_an_error_naming_it() {
        let dir = std::env::temp_dir().join(format!("amorph-store-corrupt-{}", std::process::id()));
        let store = RunStore::create(&locomotion_config(&dir, 1), true).unwrap();
        let insert = |island: i64, task: i64| {
            store
                .with(|c| {
                    c.execute(
                        "INSERT INTO population(epoch, island, slot, task_id, fitness) VALUES (0, ?1, 0, ?2, 0.0)",
                        [island, task],
                    )
                })
                .unwrap();
        };
        insert(0, 1);
        assert_eq!(store.population(0).unwrap(), [[TaskId(1)]]);
        for (island, task) in [(-1, 2), (1 << 40, 3), (1, -4)] {
            insert(island, task);
            let err = store.population(0).unwrap_err().to_string();
            assert!(err.contains("table population, row (epoch 0"), "{err}");
            assert!(err.contains(&format!("task_id {task}")), "{err}");
            store
                .with(|c| c.execute("DELETE FROM population WHERE task_id = ?1", [task]))
                .unwrap();
        }
        store
            .with(|c| {
                c.execute(
                    "INSERT INTO evaluation(task_id, epoch, island, purpose, resolution, genome, outcome, fitness, worker, wall_seconds, finished_unix) VALUES (-7, 0, 0, 'child', '', '{}', '{}', 0.0, '', 0.0, 0)",
                    [],
                )
            })
            .unwrap();
        let err = store.evaluations().unwrap_err().to_string();
        assert!(err.contains("table evaluation, row task_id -7"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The wall model learns from the stored config whether a run overlapped its finest-level
    /// checks: today's configs write the key at its default (on); a store from before the key,
    /// whose run could not overlap, reads as not. A purpose the store does not know is an error
    /// naming the task.
    #[test]
    fn a_recorded_run_says_whether_its_checks_overlapped() {
        let dir = std::env::temp_dir().join(format!("amorph-store-overlap-{}", std::process::id()));
        let config = locomotion_config(&dir, 1);
        let text = config_text(&config);
        assert!(text.contains("overlap_finest_checks = true"), "{text}");
        let store = RunStore::create(&config, true).unwrap();
        let path = store.path().to_owned();
        assert!(RunStore::peek_recorded_run(&path).unwrap().overlapped);
        let old_text: String = (text.lines())
            .filter(|line| !line.starts_with("overlap_finest_checks"))
            .map(|line| format!("{line}\n"))
            .collect();
        store
            .with(|c| {
                c.execute(
                    "UPDATE run SET value = ?1 WHERE key = 'config'",
                    [&old_text],
                )
            })
            .unwrap();
        assert!(!RunStore::peek_recorded_run(&path).unwrap().overlapped);
        store
            .with(|c| {
                c.execute(
                    "INSERT INTO evaluation(task_id, epoch, island, purpose, resolution, genome, outcome, fitness, worker, wall_seconds, finished_unix) VALUES (3, 1, 0, 'guess', '', '{}', '{}', 0.0, '', 0.5, 0)",
                    [],
                )
            })
            .unwrap();
        let err = RunStore::peek_recorded_run(&path).unwrap_err().to_string();
        assert!(
            err.contains("table evaluation, task 3: purpose \"guess\""),
            "{err}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
