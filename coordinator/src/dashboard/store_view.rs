//! The dashboard's view of a run store: opened read-only (a run may be writing it; WAL readers
//! never block the writer), every poll read in one read transaction so its figures agree with each
//! other, and the history rows of recorded epochs kept so each poll reads only the epochs since.
//!
//! The history rows are the store's `history` table: `history.csv`'s rows. A store written before
//! that table existed has them derived from its population snapshots instead, as the run derives
//! them (an island's best is its fittest slot, the first on a tie; the figure is the task's figure
//! of that design's stored outcome; the mean is over the slots that did not fail), but after the
//! epoch's migration rather than before it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use rusqlite::{Connection, OpenFlags, OptionalExtension};
use serde::Deserialize;

use super::status::{
    Best, HistoryPoint, IslandRow, Migration, Progress, RunInfo, Status, Verification, WorkerRow,
};
use crate::config::RunConfig;

/// Seconds of recent evaluations the rates and the time to the end are measured over.
const RATE_WINDOW_SECONDS: f64 = 60.0;
/// Most recent migrations listed.
const RECENT_MIGRATIONS: usize = 20;

#[derive(Debug, thiserror::Error)]
#[error("run store {path}: {message}")]
pub struct StoreViewError {
    pub path: PathBuf,
    pub message: String,
}

/// A run store as the dashboard reads it.
#[derive(Debug)]
pub struct StoreView {
    path: PathBuf,
    conn: Connection,
    config: RunConfig,
    /// History rows of every epoch read so far, in (epoch, island) order.
    history: Vec<HistoryPoint>,
    /// Each island's slots at the last epoch read: (task id, fitness).
    last_populations: BTreeMap<u32, Vec<(u64, Option<f64>)>>,
    last_epoch: Option<i64>,
    /// Tables a store written by an older coordinator may lack (they are created when a run opens
    /// it for writing; this view only reads).
    has_history: bool,
    has_checks: bool,
    /// What changes only when an epoch is recorded, read with the last epoch read.
    at_epoch: Option<AtEpoch>,
}

/// The best design, the islands and the latest migrations as of the last epoch read.
#[derive(Debug)]
struct AtEpoch {
    best: Option<Best>,
    islands: Vec<IslandRow>,
    migrations: Vec<Migration>,
}

impl StoreView {
    /// Opens the store at `path` read-only and reads the run's config from it.
    pub fn open(path: &Path) -> Result<Self, StoreViewError> {
        let fail = |message: String| StoreViewError {
            path: path.to_owned(),
            message,
        };
        if !path.is_file() {
            return Err(fail("no such file (a run folder holds run.sqlite)".into()));
        }
        let conn = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY)
            .map_err(|e| fail(e.to_string()))?;
        conn.busy_timeout(std::time::Duration::from_secs(5))
            .map_err(|e| fail(e.to_string()))?;
        let text: Option<String> = conn
            .query_row("SELECT value FROM run WHERE key = 'config'", [], |r| {
                r.get(0)
            })
            .optional()
            .map_err(|e| fail(format!("not a run store: {e}")))?;
        let text = text.ok_or_else(|| fail("no config recorded in table run".into()))?;
        // A custom profile's file is looked for beside the store, where its run left config.toml.
        let config = RunConfig::parse(&text, &path.with_file_name("config.toml"))
            .map_err(|e| fail(format!("its recorded config: {e}")))?;
        let exists = |table: &str| {
            conn.query_row(
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
                [table],
                |r| r.get::<_, i64>(0),
            )
            .map(|n| n > 0)
            .map_err(|e| fail(e.to_string()))
        };
        let has_history = exists("history")?;
        let has_checks = exists("verification")? && exists("quarantine")? && exists("unchecked")?;
        Ok(Self {
            path: path.to_owned(),
            conn,
            config,
            history: Vec::new(),
            last_populations: BTreeMap::new(),
            last_epoch: None,
            has_history,
            has_checks,
            at_epoch: None,
        })
    }

    pub fn config(&self) -> &RunConfig {
        &self.config
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What the store holds now. `now_unix` ends the window the rates are measured over (for a
    /// finished run, pass the time of its last evaluation).
    pub fn status(&mut self, now_unix: Option<f64>) -> Result<Status, StoreViewError> {
        let path = self.path.clone();
        let fail = |e: rusqlite::Error| StoreViewError {
            path: path.clone(),
            message: e.to_string(),
        };
        self.conn.execute_batch("BEGIN").map_err(fail)?;
        let status = self.read(now_unix);
        // A read transaction has nothing to keep: ending it lets the writer checkpoint the WAL.
        let _ = self.conn.execute_batch("COMMIT");
        status.map_err(|e| match e {
            Read::Sqlite(e) => fail(e),
            Read::Corrupt(message) => StoreViewError {
                path: self.path.clone(),
                message,
            },
        })
    }

    fn read(&mut self, now_unix: Option<f64>) -> Result<Status, Read> {
        if self.read_new_epochs()? || self.at_epoch.is_none() {
            self.at_epoch = Some(AtEpoch {
                best: self.best()?,
                islands: self.islands()?,
                migrations: self.migrations()?,
            });
        }
        let at_epoch = self.at_epoch.as_ref().expect("read above");
        let scene = &self.config.scene;
        let (evaluations, last_finished): (i64, Option<f64>) = self.conn.query_row(
            "SELECT COUNT(*), MAX(finished_unix) FROM evaluation",
            [],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )?;
        let now = now_unix.or(last_finished).unwrap_or(0.0);
        let since = now - RATE_WINDOW_SECONDS;
        let recent: (i64, Option<f64>) = self.conn.query_row(
            "SELECT COUNT(*), MIN(finished_unix) FROM evaluation WHERE finished_unix > ?1 AND finished_unix <= ?2",
            [since, now],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )?;
        // Measured from the window's first evaluation, so a run younger than the window is not
        // under-counted; at least a second, so a burst of two is not "infinite".
        let span = recent.1.map_or(RATE_WINDOW_SECONDS, |first| {
            (now - first).clamp(1.0, RATE_WINDOW_SECONDS)
        });
        let rate = (recent.0 >= 2).then(|| recent.0 as f64 / span);
        let budget = self.config.budget.evaluations;
        let evaluations = evaluations as u64;
        let last = self.history.last();
        let progress = Progress {
            evaluations,
            epochs: self.last_epoch.map_or(0, |e| e as u64 + 1),
            wall_seconds: last.map_or(0.0, |h| h.wall_seconds),
            resolution: last.map(|h| h.resolution.clone()),
            evaluations_per_second: rate,
            seconds_left: match (budget, rate) {
                (Some(b), Some(r)) if r > 0.0 => Some(b.saturating_sub(evaluations) as f64 / r),
                _ => None,
            },
        };
        let run = RunInfo {
            name: self.config.name.clone(),
            task: scene.kind().to_owned(),
            figure: scene.figure_spec().column.to_owned(),
            figure_axis: scene.figure_spec().axis.to_owned(),
            figure_log: scene.figure_spec().log,
            paper_figure: paper_figure(scene),
            target_figure: self.config.budget.target_rms_percent,
            budget_evaluations: budget,
            islands: self.config.search.islands,
            population: self.config.search.population,
        };
        Ok(Status {
            run,
            progress,
            history: self.history.clone(),
            best: at_epoch.best.clone(),
            islands: at_epoch.islands.clone(),
            migrations: at_epoch.migrations.clone(),
            workers: self.workers(since, now, span)?,
            queue: None,
            verification: self.verification()?,
            live: false,
        })
    }

    /// The history rows of the epochs recorded since the last poll, and whether there were
    /// any. The run writes an epoch's row, its populations and its migrations in one
    /// transaction, so an epoch is read whole or not at all.
    fn read_new_epochs(&mut self) -> Result<bool, Read> {
        let after = self.last_epoch.unwrap_or(-1);
        let epochs: Vec<(i64, i64, f64, String)> = {
            let mut stmt = self.conn.prepare(
                "SELECT epoch, evaluations, wall_seconds, resolution FROM epoch WHERE epoch > ?1 ORDER BY epoch",
            )?;
            stmt.query_map([after], |r| {
                Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?))
            })?
            .collect::<rusqlite::Result<_>>()?
        };
        for (epoch, evaluations, wall_seconds, resolution) in epochs {
            let mut islands: BTreeMap<u32, Vec<(u64, Option<f64>)>> = BTreeMap::new();
            {
                let mut stmt = self.conn.prepare_cached(
                    "SELECT island, task_id, fitness FROM population WHERE epoch = ?1 ORDER BY island, slot",
                )?;
                let rows = stmt.query_map([epoch], |r| {
                    Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)?, r.get(2)?))
                })?;
                for row in rows {
                    let (island, task, fitness) = row?;
                    let (Ok(island), Ok(task)) = (u32::try_from(island), u64::try_from(task))
                    else {
                        return Err(Read::Corrupt(format!(
                            "table population, epoch {epoch}: island {island}, task_id {task}"
                        )));
                    };
                    islands.entry(island).or_default().push((task, fitness));
                }
            }
            let recorded = self.recorded_history(epoch)?;
            let rows = if recorded.is_empty() {
                self.derived_history(&islands)?
            } else {
                recorded
            };
            for row in rows {
                self.history.push(HistoryPoint {
                    epoch: epoch as u64,
                    evaluations: evaluations as u64,
                    wall_seconds,
                    resolution: resolution.clone(),
                    ..row
                });
            }
            self.last_populations = islands;
            self.last_epoch = Some(epoch);
        }
        Ok(self.last_epoch.unwrap_or(-1) != after)
    }

    /// The epoch's rows of the `history` table (empty for a store written before it existed).
    fn recorded_history(&self, epoch: i64) -> Result<Vec<HistoryPoint>, Read> {
        if !self.has_history {
            return Ok(Vec::new());
        }
        let mut stmt = self.conn.prepare_cached(
            "SELECT island, best_fitness, best_figure, mean_fitness, replacements, hypervolume FROM history WHERE epoch = ?1 ORDER BY island",
        )?;
        let rows = stmt.query_map([epoch], |r| {
            Ok(HistoryPoint {
                island: r.get::<_, i64>(0)? as u32,
                best_fitness: r.get(1)?,
                best_figure: r.get(2)?,
                mean_fitness: r.get(3)?,
                replacements: Some(r.get::<_, i64>(4)? as u64),
                hypervolume: r.get(5)?,
                ..HistoryPoint::default()
            })
        })?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }

    /// History rows from an epoch's populations, for a store without its `history` table.
    fn derived_history(
        &self,
        islands: &BTreeMap<u32, Vec<(u64, Option<f64>)>>,
    ) -> Result<Vec<HistoryPoint>, Read> {
        let mut rows = Vec::with_capacity(islands.len());
        for (&island, slots) in islands {
            let best = fittest(slots);
            let valid: Vec<f64> = slots.iter().filter_map(|s| s.1).collect();
            let best_figure = match best {
                Some((task, Some(_))) => {
                    (self.outcome(task)?).and_then(|o| self.config.scene.figure(&o))
                }
                _ => None,
            };
            rows.push(HistoryPoint {
                island,
                best_fitness: best.and_then(|b| b.1),
                best_figure,
                mean_fitness: (!valid.is_empty())
                    .then(|| valid.iter().sum::<f64>() / valid.len() as f64),
                ..HistoryPoint::default()
            });
        }
        Ok(rows)
    }

    fn outcome(&self, task: u64) -> Result<Option<Outcome>, Read> {
        let text: Option<String> = self
            .conn
            .prepare_cached("SELECT outcome FROM evaluation WHERE task_id = ?1")?
            .query_row([task as i64], |r| r.get(0))
            .optional()?;
        text.map(|t| {
            serde_json::from_str(&t)
                .map_err(|e| Read::Corrupt(format!("evaluation {task}: its outcome: {e}")))
        })
        .transpose()
    }

    /// The fittest design of the last recorded epoch (the lowest island, then slot, on a tie),
    /// as the run's summary names it.
    fn best(&self) -> Result<Option<Best>, Read> {
        let all: Vec<(u32, u64, Option<f64>)> = (self.last_populations.iter())
            .flat_map(|(&i, slots)| slots.iter().map(move |&(t, f)| (i, t, f)))
            .collect();
        let Some(&(island, task, _)) = all
            .iter()
            .reduce(|best, x| if rank(x.2) > rank(best.2) { x } else { best })
        else {
            return Ok(None);
        };
        let row: Option<(String, String, i64, String)> = self
            .conn
            .query_row(
                "SELECT outcome, resolution, epoch, worker FROM evaluation WHERE task_id = ?1",
                [task as i64],
                |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)),
            )
            .optional()?;
        let Some((outcome_json, resolution, epoch, worker)) = row else {
            return Err(Read::Corrupt(format!(
                "table population names task {task}, which table evaluation lacks"
            )));
        };
        let corrupt =
            |e: serde_json::Error| Read::Corrupt(format!("evaluation {task}: its outcome: {e}"));
        let stored: serde_json::Value = serde_json::from_str(&outcome_json).map_err(corrupt)?;
        let outcome = Outcome::deserialize(&stored).map_err(corrupt)?;
        let scene = &self.config.scene;
        Ok(Some(Best {
            task_id: task,
            island,
            evaluated_in_epoch: epoch as u64,
            resolution,
            worker,
            fitness: outcome.fitness(),
            figure: scene.figure(&outcome),
            headline: scene.headline(&outcome),
            summary: outcome.fitness().map(|_| scene.summary(&outcome)),
            outcome: stored,
        }))
    }

    fn islands(&self) -> Result<Vec<IslandRow>, Read> {
        let mut moved: BTreeMap<(u32, u32), u64> = BTreeMap::new();
        let mut stmt = self.conn.prepare_cached(
            "SELECT from_island, to_island, COUNT(*) FROM migration GROUP BY from_island, to_island",
        )?;
        for row in stmt.query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, i64>(1)?,
                r.get::<_, i64>(2)?,
            ))
        })? {
            let (from, to, n) = row?;
            moved.insert((from as u32, to as u32), n as u64);
        }
        let last_epoch = self.last_epoch.map(|e| e as u64);
        Ok(self
            .last_populations
            .iter()
            .map(|(&island, slots)| {
                let point = (self.history.iter().rev())
                    .find(|h| h.island == island && Some(h.epoch) == last_epoch);
                IslandRow {
                    island,
                    population: slots.len(),
                    best_fitness: point.and_then(|p| p.best_fitness),
                    best_figure: point.and_then(|p| p.best_figure),
                    emigrants: (moved.iter())
                        .filter(|((from, _), _)| *from == island)
                        .map(|(_, n)| n)
                        .sum(),
                    immigrants: (moved.iter())
                        .filter(|((_, to), _)| *to == island)
                        .map(|(_, n)| n)
                        .sum(),
                }
            })
            .collect())
    }

    fn migrations(&self) -> Result<Vec<Migration>, Read> {
        let mut stmt = self.conn.prepare_cached(
            "SELECT epoch, from_island, to_island, task_id FROM migration ORDER BY rowid DESC LIMIT ?1",
        )?;
        let rows = stmt.query_map([RECENT_MIGRATIONS as i64], |r| {
            Ok(Migration {
                epoch: r.get::<_, i64>(0)? as u64,
                from_island: r.get::<_, i64>(1)? as u32,
                to_island: r.get::<_, i64>(2)? as u32,
                task_id: r.get::<_, i64>(3)? as u64,
            })
        })?;
        Ok(rows.collect::<rusqlite::Result<_>>()?)
    }

    /// Each worker that has evaluated for the run: its evaluations, its rate over the window
    /// (`since`, `now`] (whose evaluations span `span` seconds), the checks it made and whether
    /// it was quarantined.
    fn workers(&self, since: f64, now: f64, span: f64) -> Result<Vec<WorkerRow>, Read> {
        let mut rows: BTreeMap<String, WorkerRow> = BTreeMap::new();
        let mut stmt = self.conn.prepare_cached(
            "SELECT worker, COUNT(*), SUM(finished_unix > ?1 AND finished_unix <= ?2) FROM evaluation GROUP BY worker",
        )?;
        for row in stmt.query_map([since, now], |r| {
            Ok((
                r.get::<_, String>(0)?,
                r.get::<_, i64>(1)?,
                r.get::<_, i64>(2)?,
            ))
        })? {
            let (label, n, recent) = row?;
            let w = rows
                .entry(label.clone())
                .or_insert_with(|| WorkerRow::named(label));
            w.evaluations = n as u64;
            w.evaluations_per_second = recent as f64 / span;
        }
        if !self.has_checks {
            return Ok(rows.into_values().collect());
        }
        // A check's `checker` names its workers as the evaluations do (`name (id)`), several
        // joined by ", then " when a disagreement took more than one.
        let mut stmt = self
            .conn
            .prepare_cached("SELECT checker, COUNT(*) FROM verification GROUP BY checker")?;
        for row in stmt.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, i64>(1)?)))? {
            let (checkers, n) = row?;
            for label in checkers.split(", then ") {
                rows.entry(label.to_owned())
                    .or_insert_with(|| WorkerRow::named(label.to_owned()))
                    .checks += n as u64;
            }
        }
        // A quarantine names the worker by its id and principal (`w3-1a2b3c (credential x)`).
        let mut stmt = self
            .conn
            .prepare_cached("SELECT DISTINCT worker FROM quarantine")?;
        for row in stmt.query_map([], |r| r.get::<_, String>(0))? {
            let caught = row?;
            let id = caught.split_whitespace().next().unwrap_or_default();
            let label = (rows.keys())
                .find(|label| label.ends_with(&format!("({id})")))
                .cloned()
                .unwrap_or(caught);
            rows.entry(label.clone())
                .or_insert_with(|| WorkerRow::named(label))
                .quarantined = true;
        }
        Ok(rows.into_values().collect())
    }

    fn verification(&self) -> Result<Verification, Read> {
        if !self.has_checks {
            return Ok(Verification::default());
        }
        Ok(self.conn.query_row(
            "SELECT (SELECT COUNT(*) FROM verification), (SELECT COUNT(*) FROM verification WHERE NOT agreed), (SELECT COUNT(DISTINCT worker) FROM quarantine), (SELECT COUNT(*) FROM unchecked)",
            [],
            |r| {
                Ok(Verification {
                    checks: r.get::<_, i64>(0)? as u64,
                    disagreements: r.get::<_, i64>(1)? as u64,
                    quarantined_workers: r.get::<_, i64>(2)? as u64,
                    unchecked_claims: r.get::<_, i64>(3)? as u64,
                })
            },
        )?)
    }

    /// The genome and resolution of evaluation `task`, for its picture.
    pub fn design(&self, task: u64) -> Result<Option<(Genome, GridDims)>, StoreViewError> {
        let fail = |message: String| StoreViewError {
            path: self.path.clone(),
            message: format!("evaluation {task}: {message}"),
        };
        let row: Option<(String, String)> = self
            .conn
            .query_row(
                "SELECT genome, resolution FROM evaluation WHERE task_id = ?1",
                [task as i64],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
            .map_err(|e| fail(e.to_string()))?;
        let Some((genome, resolution)) = row else {
            return Ok(None);
        };
        let genome: Genome =
            serde_json::from_str(&genome).map_err(|e| fail(format!("its genome: {e}")))?;
        let dims =
            parse_dims(&resolution).ok_or_else(|| fail(format!("resolution {resolution:?}")))?;
        Ok(Some((genome, dims)))
    }
}

enum Read {
    Sqlite(rusqlite::Error),
    Corrupt(String),
}

impl From<rusqlite::Error> for Read {
    fn from(e: rusqlite::Error) -> Self {
        Self::Sqlite(e)
    }
}

/// Failures rank below every evaluated design, as `Outcome::rank` orders them.
fn rank(fitness: Option<f64>) -> f64 {
    fitness.unwrap_or(f64::NEG_INFINITY)
}

/// The fittest slot, the first on a tie (`Island::best`).
fn fittest(slots: &[(u64, Option<f64>)]) -> Option<(u64, Option<f64>)> {
    slots
        .iter()
        .copied()
        .reduce(|best, x| if rank(x.1) > rank(best.1) { x } else { best })
}

fn parse_dims(text: &str) -> Option<GridDims> {
    let counts: Vec<u64> = text
        .split('x')
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    match counts[..] {
        [nx, ny, nz] => amorph_proto::grid::checked_grid([nx, ny, nz]).ok(),
        _ => None,
    }
}

/// The paper's value of the task's figure where the paper has one: Table III's simulated RMS
/// error for its four beams. (The robot's figure is its travel in mm, which the paper does not
/// give; its speed beside the paper's is in the best design's summary.)
fn paper_figure(scene: &Scene) -> Option<f64> {
    match scene {
        Scene::Beam(beam) => beam.target.paper_rms_percent(),
        _ => None,
    }
}
