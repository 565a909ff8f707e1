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
//! - `history(epoch, island, best_fitness, best_figure, mean_fitness, replacements, hypervolume)`:
//!   `history.csv`'s rows (taken before the epoch's migration; the populations after it).
//!
//! Files: `records` (what a run writes), `read` (what a resume reads back), `peek` (read-only
//! looks at a store a run may be writing), `schema` (the tables).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rusqlite::{Connection, OptionalExtension, params};

use crate::config::RunConfig;

mod peek;
mod read;
mod records;
mod schema;
#[cfg(test)]
mod tests;

pub use records::{EpochRecord, EvaluationRecord, MigrationRecord, Purpose, StoredEvaluation};
use schema::{ADDED_SCHEMA, SCHEMA};

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
        "run store {path} was made by a different config ({differs} differs); only [budget], [cluster], [dashboard] and results_dir may change on --resume"
    )]
    ConfigChanged { path: PathBuf, differs: String },
    #[error("run store {path}: {message}")]
    Corrupt { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, StoreError>;

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
            c.execute_batch(ADDED_SCHEMA)?;
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
    ///
    /// The tables and the index added since the first format are created here, so a store
    /// written before they existed resumes with them (the tables empty).
    pub fn resume(config: &RunConfig) -> Result<Self> {
        let path = Self::path_for(config);
        if !path.exists() {
            return Err(StoreError::Missing(path));
        }
        let store = Self::open_file(&path)?;
        store.with(|c| c.execute_batch(ADDED_SCHEMA))?;
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
        // price of not syncing each evaluation to disk).
        store.with(|c| {
            c.pragma_update(None, "journal_mode", "WAL")?;
            c.pragma_update(None, "synchronous", "NORMAL")?;
            c.busy_timeout(std::time::Duration::from_secs(10))?;
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
}

pub(crate) fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

fn config_text(config: &RunConfig) -> String {
    toml::to_string(&config.to_raw()).expect("configs serialize")
}

/// The first key (dotted) whose value differs between two configs, ignoring `budget` (a run may
/// be extended), `cluster` and `dashboard` (how workers connect and who watches never change a
/// result) and `results_dir` (a
/// stopped run's folder may be moved, e.g. from a lent machine to the one that finishes it: the
/// store is found through the new path, so nothing of the old one is read).
fn first_difference(a: &toml::Table, b: &toml::Table) -> Option<String> {
    first_difference_except(a, b, &["budget", "cluster", "dashboard", "results_dir"])
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
