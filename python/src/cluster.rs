//! `amorph.Cluster`: a coordinator inside the Python process that evaluates the batches an
//! optimizer of the caller's asks for, on its local workers and any `worker --connect` that
//! joins, with the config's token, TLS and verification, recording every evaluation in a run
//! store ([`amorph_coordinator::asked`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::voxel::GridDims;
use amorph_coordinator::asked::AskedRun;
use amorph_coordinator::job::{JobOptions, StoreMode};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::genome::PyGenome;
use crate::interrupt::interruptible;
use crate::outcome::PyOutcome;
use crate::runs::load_config;
use crate::scene::{PyScene, check_genome};

/// A coordinator serving evaluations to whoever asks from Python.
#[pyclass(name = "Cluster", module = "amorph", frozen)]
#[derive(Debug)]
pub struct PyCluster {
    run: Mutex<Option<AskedRun>>,
    shutdown: Arc<AtomicBool>,
    scene: Arc<Scene>,
    finest: GridDims,
    url: String,
    store: PathBuf,
}

#[pymethods]
impl PyCluster {
    /// Starts a coordinator for `config` (a path, or None for the quickstart's scene) with
    /// `overrides` as in `amorph.run`. `local_workers` evaluate in this process (default: the
    /// config's `cluster.local_workers`); `listen` is where remote workers connect.
    #[new]
    #[pyo3(signature = (config = None, *, local_workers = None, listen = None, resume = false, fresh = false, **overrides))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        config: Option<PathBuf>,
        local_workers: Option<usize>,
        listen: Option<String>,
        resume: bool,
        fresh: bool,
        overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        if resume && fresh {
            return Err(PyValueError::new_err(
                "resume and fresh exclude each other: resume continues the stored run, fresh deletes it",
            ));
        }
        let py_overrides = match overrides {
            Some(d) => d.clone(),
            None => PyDict::new(py),
        };
        let config = load_config(config, &py_overrides)?;
        let shutdown = Arc::new(AtomicBool::new(false));
        let options = JobOptions {
            store: if resume {
                StoreMode::Resume
            } else if fresh {
                StoreMode::Fresh
            } else {
                StoreMode::New
            },
            listen,
            local_workers,
            shutdown: shutdown.clone(),
            ..JobOptions::default()
        };
        let run = AskedRun::start(&config, options)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(Self {
            url: run.url().to_owned(),
            store: run.store_path().to_owned(),
            run: Mutex::new(Some(run)),
            shutdown,
            scene: Arc::new(config.scene.clone()),
            finest: config.resolution.finest(),
        })
    }

    /// Evaluates a batch and returns its outcomes in order: deterministic, whatever the workers.
    /// `genomes` are Genome objects or (N, 6) arrays; `resolution` defaults to the config's
    /// finest. Ctrl-C stops the batch (what finished stays in the store) and raises
    /// KeyboardInterrupt; the cluster is then stopped.
    #[pyo3(signature = (genomes, resolution = None))]
    fn evaluate(
        &self,
        py: Python<'_>,
        genomes: Vec<Bound<'_, PyAny>>,
        resolution: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Vec<PyOutcome>> {
        let dims = match resolution {
            Some(r) => crate::convert::resolution(r)?,
            None => self.finest,
        };
        let genomes = genomes
            .iter()
            .enumerate()
            .map(|(i, g)| {
                genome(g)
                    .and_then(|g| check_genome(&self.scene, &g).map(|()| g))
                    .map_err(|e| PyValueError::new_err(format!("genomes[{i}]: {}", e.value(py))))
            })
            .collect::<PyResult<Vec<Genome>>>()?;
        self.scene
            .check_dims(dims)
            .map_err(|e| PyValueError::new_err(format!("resolution {dims}: {e}")))?;
        let mut guard = self.run.lock().unwrap_or_else(|e| e.into_inner());
        let Some(run) = guard.as_mut() else {
            return Err(PyRuntimeError::new_err("the cluster is closed"));
        };
        let shutdown = &self.shutdown;
        let outcomes = interruptible(
            py,
            || shutdown.store(true, Ordering::Relaxed),
            || run.evaluate(&genomes, dims),
        )?
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(outcomes
            .into_iter()
            .map(|o| PyOutcome::new(o, &self.scene))
            .collect())
    }

    /// The scene the cluster evaluates in.
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            inner: self.scene.clone(),
        }
    }

    /// Where remote workers connect: `worker --connect URL`.
    #[getter]
    fn url(&self) -> &str {
        &self.url
    }

    /// The run store that records every evaluation (`amorph.open_run` reads it).
    #[getter]
    fn store(&self) -> PathBuf {
        self.store.clone()
    }

    /// Evaluations asked so far.
    #[getter]
    fn evaluations(&self) -> u64 {
        let guard = self.run.lock().unwrap_or_else(|e| e.into_inner());
        guard.as_ref().map_or(0, AskedRun::evaluations)
    }

    /// Stops the coordinator: remote workers are told the run is over (after a Ctrl-C they wait
    /// for its resumption instead). Closing twice does nothing.
    fn close(&self, py: Python<'_>) {
        let run = self.run.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(run) = run {
            py.detach(|| run.close());
        }
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_exc))]
    fn __exit__(&self, py: Python<'_>, _exc: &Bound<'_, pyo3::types::PyTuple>) {
        self.close(py);
    }

    fn __repr__(&self) -> String {
        format!(
            "Cluster(url={:?}, store={:?})",
            self.url,
            self.store.display().to_string()
        )
    }
}

impl Drop for PyCluster {
    fn drop(&mut self) {
        let run = self.run.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(run) = run {
            run.close();
        }
    }
}

/// A Genome, or an array-like Genome accepts.
fn genome(value: &Bound<'_, PyAny>) -> PyResult<Genome> {
    match value.cast::<PyGenome>() {
        Ok(g) => Ok(g.get().inner.clone()),
        Err(_) => Ok(PyGenome::from_array_like(value)?.inner),
    }
}
