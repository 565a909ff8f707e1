//! Read-only looks at a store, safe while a run is writing it: for the wall-time model, for a
//! watcher counting evaluations, and for the hostile-peer checks.

use std::path::Path;

use rusqlite::{Connection, OptionalExtension};

use super::{Purpose, Result, RunStore, StoreError};
use crate::run::schedule::RecordedRun;

impl RunStore {
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
}

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
