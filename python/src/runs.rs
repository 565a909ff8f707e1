//! `amorph.run` underneath: a whole coordinator job (the search, the run store, local workers and
//! any remote `worker --connect`) on a thread of its own, heard epoch by epoch.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use amorph_coordinator::RunConfig;
use amorph_coordinator::config::Override;
use amorph_coordinator::job::{JobOptions, StoreMode, run_job};
use amorph_coordinator::progress::Progress;
use amorph_coordinator::summary::{HistoryRow, RunSummary};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::{json_to_py, py_to_toml};
use crate::genome::PyGenome;
use crate::outcome::PyOutcome;

#[derive(Debug)]
enum Event {
    Epoch(Vec<HistoryRow>),
    Done(Result<RunSummary, String>),
}

/// A run going on in this process. `amorph.run` and `amorph.Run` drive it; it is not meant to
/// be used directly.
#[pyclass(name = "RunHandle", module = "amorph._amorph", frozen)]
#[derive(Debug)]
pub struct PyRunHandle {
    events: Mutex<mpsc::Receiver<Event>>,
    shutdown: Arc<AtomicBool>,
    thread: Mutex<Option<JoinHandle<()>>>,
    config: RunConfig,
}

#[pymethods]
impl PyRunHandle {
    /// Starts `config` (a path, or None for the quickstart) with `overrides` (a dict of keys,
    /// nested dicts for tables), as `coordinator --config PATH --set key=value` would.
    #[new]
    #[pyo3(signature = (config, overrides, *, resume = false, fresh = false, local_workers = None, listen = None))]
    fn new(
        config: Option<PathBuf>,
        overrides: &Bound<'_, PyDict>,
        resume: bool,
        fresh: bool,
        local_workers: Option<usize>,
        listen: Option<String>,
    ) -> PyResult<Self> {
        let store = store_mode(resume, fresh)?;
        let config = load_config(config, overrides)?;
        let (tx, events) = mpsc::channel();
        let shutdown = Arc::new(AtomicBool::new(false));
        let epochs = tx.clone();
        let options = JobOptions {
            store,
            listen,
            local_workers,
            progress: Progress::observed(move |rows| {
                let _ = epochs.send(Event::Epoch(rows.to_vec()));
            }),
            shutdown: shutdown.clone(),
            ..JobOptions::default()
        };
        let job_config = config.clone();
        let thread = std::thread::Builder::new()
            .name("amorph-run".into())
            .spawn(move || {
                let result = run_job(&job_config, options).map_err(|e| e.to_string());
                let _ = tx.send(Event::Done(result));
            })
            .map_err(|e| PyRuntimeError::new_err(format!("starting the run: {e}")))?;
        Ok(Self {
            events: Mutex::new(events),
            shutdown,
            thread: Mutex::new(Some(thread)),
            config,
        })
    }

    /// The next event within `timeout` seconds, or None: `("epoch", dict)` at the end of each
    /// epoch, then `("done", dict)` once. A failed run raises RuntimeError.
    fn next_event<'py>(
        &self,
        py: Python<'py>,
        timeout: f64,
    ) -> PyResult<Option<Bound<'py, PyTuple>>> {
        let wait = Duration::try_from_secs_f64(timeout.max(0.0)).unwrap_or(Duration::MAX);
        let event = py.detach(|| {
            let events = self.events.lock().unwrap_or_else(|e| e.into_inner());
            events.recv_timeout(wait)
        });
        py.check_signals()?;
        match event {
            Ok(Event::Epoch(rows)) => Ok(Some(PyTuple::new(
                py,
                [
                    "epoch".into_pyobject(py)?.into_any(),
                    epoch_dict(py, &rows)?.into_any(),
                ],
            )?)),
            Ok(Event::Done(result)) => {
                self.join();
                match result {
                    Ok(summary) => Ok(Some(PyTuple::new(
                        py,
                        [
                            "done".into_pyobject(py)?.into_any(),
                            summary_dict(py, &summary, &self.config)?.into_any(),
                        ],
                    )?)),
                    Err(message) => Err(PyRuntimeError::new_err(message)),
                }
            }
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => {
                Err(PyRuntimeError::new_err("the run has already ended"))
            }
        }
    }

    /// Asks the run to stop: it stops mid-batch, keeping every finished evaluation in its store,
    /// and can be resumed (`resume=True`) to the same bits.
    fn stop(&self) {
        self.shutdown.store(true, Ordering::Relaxed);
    }

    /// The run's results folder.
    #[getter]
    fn run_dir(&self) -> PathBuf {
        self.config.run_dir()
    }
}

impl PyRunHandle {
    fn join(&self) {
        let thread = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(thread) = thread {
            let _ = thread.join();
        }
    }
}

impl Drop for PyRunHandle {
    /// A handle dropped mid-run (its Python object collected) stops the run rather than leaving
    /// it running unheard.
    fn drop(&mut self) {
        self.shutdown.store(true, Ordering::Relaxed);
        self.join();
    }
}

/// How to open the run store: `resume` continues it, `fresh` deletes it first, neither makes a
/// new one (an existing store is then an error).
pub fn store_mode(resume: bool, fresh: bool) -> PyResult<StoreMode> {
    match (resume, fresh) {
        (true, true) => Err(PyValueError::new_err(
            "resume and fresh exclude each other: resume continues the stored run, fresh deletes it",
        )),
        (true, false) => Ok(StoreMode::Resume),
        (false, true) => Ok(StoreMode::Fresh),
        (false, false) => Ok(StoreMode::New),
    }
}

/// The config at `path` (None: the quickstart) with `overrides` applied as `--set` would.
pub fn load_config(path: Option<PathBuf>, overrides: &Bound<'_, PyDict>) -> PyResult<RunConfig> {
    let mut sets = Vec::new();
    for (key, value) in overrides.iter() {
        let key: String = key.extract()?;
        flatten(&key, &py_to_toml(&value, &key)?, &mut sets);
    }
    let config = match path {
        Some(path) => RunConfig::load_with(&path, &sets),
        None => RunConfig::quickstart(&sets),
    };
    config.map_err(|e| PyValueError::new_err(e.to_string()))
}

/// `budget={"evaluations": 2000}` as the override `budget.evaluations = 2000`: a nested table
/// sets its keys one by one, so the rest of the config's table stays.
fn flatten(key: &str, value: &toml::Value, sets: &mut Vec<Override>) {
    match value {
        toml::Value::Table(table) if !table.is_empty() => {
            for (k, v) in table {
                flatten(&format!("{key}.{k}"), v, sets);
            }
        }
        _ => sets.push(Override {
            path: key.split('.').map(str::to_owned).collect(),
            value: value.clone(),
            text: format!("{key}={value}"),
        }),
    }
}

fn epoch_dict<'py>(py: Python<'py>, rows: &[HistoryRow]) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    let Some(first) = rows.first() else {
        return Ok(dict);
    };
    let best = rows
        .iter()
        .filter(|r| r.best_fitness.is_some())
        .max_by(|a, b| {
            a.best_fitness
                .partial_cmp(&b.best_fitness)
                .unwrap_or(std::cmp::Ordering::Equal)
        });
    dict.set_item("epoch", first.epoch)?;
    dict.set_item("evaluations", first.evaluations)?;
    dict.set_item("wall_seconds", first.wall_seconds)?;
    dict.set_item("resolution", &first.resolution)?;
    dict.set_item("best_fitness", best.and_then(|r| r.best_fitness))?;
    dict.set_item("best_figure", best.and_then(|r| r.best_figure))?;
    let islands = serde_json::to_value(rows).map_err(|e| PyValueError::new_err(e.to_string()))?;
    dict.set_item("islands", json_to_py(py, &islands)?)?;
    Ok(dict)
}

fn summary_dict<'py>(
    py: Python<'py>,
    summary: &RunSummary,
    config: &RunConfig,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    let best = summary.best();
    let stop =
        serde_json::to_value(summary.stop).map_err(|e| PyValueError::new_err(e.to_string()))?;
    dict.set_item("stop", json_to_py(py, &stop)?)?;
    dict.set_item("epochs", summary.epochs)?;
    dict.set_item("evaluations", summary.evaluations)?;
    dict.set_item("wall_seconds", summary.wall_seconds)?;
    dict.set_item("resolution", summary.dims.to_string())?;
    dict.set_item(
        "best_genome",
        PyGenome {
            inner: best.genome.clone(),
        },
    )?;
    dict.set_item(
        "best_outcome",
        PyOutcome::new(best.outcome.clone(), &config.scene),
    )?;
    dict.set_item("best_task", best.task.0)?;
    let dir = config.run_dir();
    dict.set_item("report", dir.join("report.html"))?;
    dict.set_item("run_dir", dir)?;
    Ok(dict)
}
