//! Read-only looks at a store, safe while a run is writing it: for a watcher counting
//! evaluations, and for the hostile-peer checks.

use std::path::Path;

use rusqlite::Connection;

use super::{Result, RunStore, StoreError};

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
