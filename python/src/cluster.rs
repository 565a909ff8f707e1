//! `amorph.Cluster`: a coordinator inside the Python process that evaluates the batches an
//! optimizer of the caller's asks for, on its local workers and any `worker --connect` that
//! joins, with the config's token, TLS and verification, recording every evaluation in a run
//! store ([`amorph_coordinator::asked`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::voxel::GridDims;
use amorph_coordinator::asked::AskedRun;
use amorph_coordinator::job::JobOptions;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::genome::PyGenome;
use crate::interrupt::interruptible;
use crate::outcome::PyOutcome;
use crate::runs::{load_config, store_mode};
use crate::scene::{PyScene, check_genome};

/// A coordinator serving evaluations to whoever asks from Python.
#[pyclass(name = "Cluster", module = "amorph", frozen)]
#[derive(Debug)]
pub struct PyCluster {
    run: Mutex<Option<AskedRun>>,
    /// Evaluations asked so far, readable while a batch runs.
    evaluations: AtomicU64,
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
        let store = store_mode(resume, fresh)?;
        let py_overrides = match overrides {
            Some(d) => d.clone(),
            None => PyDict::new(py),
        };
        let config = load_config(config, &py_overrides)?;
        let shutdown = Arc::new(AtomicBool::new(false));
        let options = JobOptions {
            store,
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
            evaluations: AtomicU64::new(run.evaluations()),
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
        let mut guard = self.idle()?;
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
        self.evaluations.store(run.evaluations(), Ordering::Relaxed);
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
        self.evaluations.load(Ordering::Relaxed)
    }

    /// Stops the coordinator: remote workers are told the run is over (after a Ctrl-C they wait
    /// for its resumption instead). Closing twice does nothing.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        let run = self.idle()?.take();
        if let Some(run) = run {
            py.detach(|| run.close());
        }
        Ok(())
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_exc))]
    fn __exit__(&self, py: Python<'_>, _exc: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<()> {
        self.close(py)
    }

    fn __repr__(&self) -> String {
        format!(
            "Cluster(url={:?}, store={:?})",
            self.url,
            self.store.display().to_string()
        )
    }
}

impl PyCluster {
    /// The run, unless another Python thread is in `evaluate`: waiting for it here, holding the
    /// GIL, would keep that thread from the GIL it needs to look at signals.
    fn idle(&self) -> PyResult<std::sync::MutexGuard<'_, Option<AskedRun>>> {
        match self.run.try_lock() {
            Ok(guard) => Ok(guard),
            Err(std::sync::TryLockError::Poisoned(e)) => Ok(e.into_inner()),
            Err(std::sync::TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "the cluster is evaluating a batch for another thread: one batch at a time",
            )),
        }
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
