//! `amorph.open_run` underneath: a run store's tables read into numpy columns, read-only, so a
//! run that another process is writing (the store is in WAL mode) can be read as it goes.

use std::path::{Path, PathBuf};

use numpy::PyArray1;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rusqlite::{Connection, OpenFlags};

#[derive(Clone, Copy)]
enum Column {
    /// int64; a NULL is -1.
    Int,
    /// float64; a NULL is NaN.
    Float,
    /// A list of str.
    Text,
}

use Column::{Float, Int, Text};

/// A table a user reads: its name here, the query, and its columns with their types.
struct TableSpec {
    name: &'static str,
    sql: &'static str,
    columns: &'static [(&'static str, Column)],
}

/// Each table a user reads, from the store's schema (`store/schema.rs` of the coordinator).
const TABLES: &[TableSpec] = &[
    TableSpec {
        name: "evaluations",
        sql: "SELECT task_id, epoch, island, purpose, resolution, fitness, worker, wall_seconds, finished_unix, genome, outcome FROM evaluation ORDER BY task_id",
        columns: &[
            ("task_id", Int),
            ("epoch", Int),
            ("island", Int),
            ("purpose", Text),
            ("resolution", Text),
            ("fitness", Float),
            ("worker", Text),
            ("wall_seconds", Float),
            ("finished_unix", Float),
            ("genome", Text),
            ("outcome", Text),
        ],
    },
    TableSpec {
        name: "epochs",
        sql: "SELECT epoch, evaluations, wall_seconds, resolution, best_fitness FROM epoch ORDER BY epoch",
        columns: &[
            ("epoch", Int),
            ("evaluations", Int),
            ("wall_seconds", Float),
            ("resolution", Text),
            ("best_fitness", Float),
        ],
    },
    TableSpec {
        name: "populations",
        sql: "SELECT epoch, island, slot, task_id, fitness FROM population ORDER BY epoch, island, slot",
        columns: &[
            ("epoch", Int),
            ("island", Int),
            ("slot", Int),
            ("task_id", Int),
            ("fitness", Float),
        ],
    },
    TableSpec {
        name: "migrations",
        sql: "SELECT epoch, from_island, to_island, emigrant_slot, replaced_slot, task_id FROM migration ORDER BY rowid",
        columns: &[
            ("epoch", Int),
            ("from_island", Int),
            ("to_island", Int),
            ("emigrant_slot", Int),
            ("replaced_slot", Int),
            ("task_id", Int),
        ],
    },
];

/// The store's tables as `{table: {column: values}}` plus its `config` (TOML text) and `path`.
/// `path` is a run's folder or its `run.sqlite`.
#[pyfunction]
pub fn read_run_store<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let file = if path.is_dir() {
        path.join("run.sqlite")
    } else {
        path
    };
    if !file.is_file() {
        return Err(PyOSError::new_err(format!(
            "{}: no run store there (a run folder holds run.sqlite)",
            file.display()
        )));
    }
    let conn = Connection::open_with_flags(
        &file,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(|e| store_error(&file, e))?;
    // One read transaction, so every table is read at the same moment of a run that goes on.
    conn.execute_batch("BEGIN")
        .map_err(|e| store_error(&file, e))?;
    let config: String = conn
        .query_row("SELECT value FROM run WHERE key = 'config'", [], |r| {
            r.get(0)
        })
        .map_err(|e| store_error(&file, e))?;
    let dict = PyDict::new(py);
    dict.set_item("path", &file)?;
    dict.set_item("config", config)?;
    for spec in TABLES {
        let columns =
            table(py, &conn, spec.sql, spec.columns).map_err(|e| store_error(&file, e))??;
        dict.set_item(spec.name, columns)?;
    }
    let _ = conn.execute_batch("COMMIT");
    Ok(dict)
}

fn table<'py>(
    py: Python<'py>,
    conn: &Connection,
    sql: &str,
    columns: &[(&str, Column)],
) -> rusqlite::Result<PyResult<Bound<'py, PyDict>>> {
    let mut ints: Vec<Vec<i64>> = vec![Vec::new(); columns.len()];
    let mut floats: Vec<Vec<f64>> = vec![Vec::new(); columns.len()];
    let mut texts: Vec<Vec<String>> = vec![Vec::new(); columns.len()];
    let mut stmt = conn.prepare(sql)?;
    let mut rows = stmt.query([])?;
    while let Some(row) = rows.next()? {
        for (i, (_, kind)) in columns.iter().enumerate() {
            match kind {
                Int => ints[i].push(row.get::<_, Option<i64>>(i)?.unwrap_or(-1)),
                Float => floats[i].push(row.get::<_, Option<f64>>(i)?.unwrap_or(f64::NAN)),
                Text => texts[i].push(row.get(i)?),
            }
        }
    }
    let build = || -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (i, (name, kind)) in columns.iter().enumerate() {
            match kind {
                Int => dict.set_item(*name, PyArray1::from_vec(py, ints[i].clone()))?,
                Float => dict.set_item(*name, PyArray1::from_vec(py, floats[i].clone()))?,
                Text => dict.set_item(*name, PyList::new(py, &texts[i])?)?,
            }
        }
        Ok(dict)
    };
    Ok(build())
}

fn store_error(path: &Path, e: rusqlite::Error) -> PyErr {
    PyValueError::new_err(format!("run store {}: {e}", path.display()))
}
