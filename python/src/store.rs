//! `amorph.open_run` underneath: a run store's tables read into numpy columns, read-only, so a
//! run that another process is writing (the store is in WAL mode) can be read as it goes.

use std::path::{Path, PathBuf};

use numpy::PyArray1;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rusqlite::{Connection, OpenFlags};

/// A column's type in Python.
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
    // SQLite's part runs without the GIL; only the Python objects are made with it.
    let (config, tables) = py
        .detach(|| read_tables(&file))
        .map_err(|e| store_error(&file, e))?;
    let dict = PyDict::new(py);
    dict.set_item("path", &file)?;
    dict.set_item("config", config)?;
    for (spec, columns) in TABLES.iter().zip(tables) {
        let table = PyDict::new(py);
        for ((name, _), values) in spec.columns.iter().zip(columns) {
            match values {
                Values::Int(v) => table.set_item(*name, PyArray1::from_vec(py, v))?,
                Values::Float(v) => table.set_item(*name, PyArray1::from_vec(py, v))?,
                Values::Text(v) => table.set_item(*name, PyList::new(py, v)?)?,
            }
        }
        dict.set_item(spec.name, table)?;
    }
    Ok(dict)
}

/// One column's values.
enum Values {
    Int(Vec<i64>),
    Float(Vec<f64>),
    Text(Vec<String>),
}

/// The config and every table's columns, in one read transaction so that all are read at the
/// same moment of a run that goes on.
fn read_tables(file: &Path) -> rusqlite::Result<(String, Vec<Vec<Values>>)> {
    let conn = Connection::open_with_flags(
        file,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )?;
    conn.execute_batch("BEGIN")?;
    let config: String = conn.query_row("SELECT value FROM run WHERE key = 'config'", [], |r| {
        r.get(0)
    })?;
    let tables = TABLES
        .iter()
        .map(|spec| read_table(&conn, spec))
        .collect::<rusqlite::Result<Vec<_>>>()?;
    conn.execute_batch("COMMIT")?;
    Ok((config, tables))
}

fn read_table(conn: &Connection, spec: &TableSpec) -> rusqlite::Result<Vec<Values>> {
    let mut columns: Vec<Values> = spec
        .columns
        .iter()
        .map(|(_, kind)| match kind {
            Int => Values::Int(Vec::new()),
            Float => Values::Float(Vec::new()),
            Text => Values::Text(Vec::new()),
        })
        .collect();
    let mut stmt = conn.prepare(spec.sql)?;
    let mut rows = stmt.query([])?;
    while let Some(row) = rows.next()? {
        for (i, column) in columns.iter_mut().enumerate() {
            match column {
                Values::Int(v) => v.push(row.get::<_, Option<i64>>(i)?.unwrap_or(-1)),
                Values::Float(v) => v.push(row.get::<_, Option<f64>>(i)?.unwrap_or(f64::NAN)),
                Values::Text(v) => v.push(row.get(i)?),
            }
        }
    }
    Ok(columns)
}

fn store_error(path: &Path, e: rusqlite::Error) -> PyErr {
    PyValueError::new_err(format!("run store {}: {e}", path.display()))
}
