//! `amorph.Scene`: a task's scene (beam, locomotion, stiffness), and what can be done with a
//! genome in it: voxelize, evaluate one or many, export its fabrication files.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use amorph::dynamics::EvaluationThreads;
use amorph::export::PrintPitch;
use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::task::scene_toml::{self, SceneAt};
use amorph::voxel::GridDims;
use amorph_worker::export::{ExportOptions, export_design};
use numpy::{PyArray1, PyArray3, PyArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{py_to_toml, resolution};
use crate::genome::PyGenome;
use crate::interrupt::interruptible;
use crate::outcome::PyOutcome;

/// Most threads a call may ask for, as for `worker --threads`.
const MAX_THREADS: usize = amorph_worker::client::MAX_THREADS;

/// What a genome is judged in: the task (`kind`), its materials, loads and goal.
#[pyclass(name = "Scene", module = "amorph", frozen)]
#[derive(Clone, Debug)]
pub struct PyScene {
    pub inner: Arc<Scene>,
}

#[pymethods]
impl PyScene {
    /// A scene from keyword arguments, as the `[scene]` table of a config would hold them:
    /// `Scene(kind="beam", profile="circular_arc")`.
    #[new]
    #[pyo3(signature = (**keys))]
    fn new(keys: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut table = toml::Table::new();
        if let Some(keys) = keys {
            for (k, v) in keys.iter() {
                let k: String = k.extract()?;
                let value = py_to_toml(&v, &format!("scene.{k}"))?;
                table.insert(k, value);
            }
        }
        let text = toml::to_string(&table).map_err(|e| PyValueError::new_err(e.to_string()))?;
        // The text is ours, not the caller's: its line numbers mean nothing to them.
        scene(&text, SceneAt::Document, Path::new("."), "Scene(...)").map_err(|e| {
            let message = e.to_string();
            let unnumbered = match message.split_once(": line ") {
                Some((source, rest)) => rest
                    .split_once(": ")
                    .map_or(message.clone(), |(_, m)| format!("{source}: {m}")),
                None => message,
            };
            PyValueError::new_err(unnumbered)
        })
    }

    /// A scene from a TOML file: a run config (its `[scene]` is used) or a bare scene table.
    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Self> {
        amorph_worker::read_scene(&path)
            .map(|s| Self { inner: Arc::new(s) })
            .map_err(|e| match e {
                amorph_worker::WorkerError::Read { .. } => PyOSError::new_err(format!("{e}")),
                _ => PyValueError::new_err(e.to_string()),
            })
    }

    /// A scene from TOML text: a run config (its `[scene]` is used) or a bare scene table. Files
    /// it names (a custom profile's CSV) are read relative to `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir = None))]
    fn from_toml(text: &str, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let document: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let (line, message) = scene_toml::locate(text, &e);
            PyValueError::new_err(format!("scene TOML, line {line}: {message}"))
        })?;
        let at = if document.contains_key("scene") {
            SceneAt::Config
        } else {
            SceneAt::Document
        };
        let base = base_dir.unwrap_or_else(|| PathBuf::from("."));
        scene(text, at, &base, "scene TOML")
    }

    /// The task: `beam`, `locomotion` or `stiffness`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// The palette's material names; a genome's material column indexes this list.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.inner
            .palette()
            .0
            .iter()
            .map(|m| m.name.clone())
            .collect()
    }

    /// The genome limits: `density` and `falloff` as (low, high), `max_points`, `min_points`.
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let limits = self.inner.limits();
        let dict = PyDict::new(py);
        dict.set_item("density", (limits.density[0], limits.density[1]))?;
        dict.set_item("falloff", (limits.falloff[0], limits.falloff[1]))?;
        dict.set_item("max_points", limits.max_points)?;
        dict.set_item("min_points", limits.min_points)?;
        Ok(dict)
    }

    /// The material index of each voxel as an int16 array of shape (nx, ny, nz), -1 where empty:
    /// the voxels the task uses (a beam keeps those connected to its clamped layer), as a run's
    /// `best_voxels.json` holds them.
    fn voxelize<'py>(
        &self,
        py: Python<'py>,
        genome: &PyGenome,
        resolution: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<i16>>> {
        let dims = self.checked(&genome.inner, resolution)?;
        let scene = self.inner.clone();
        let genome = genome.inner.clone();
        let cells = py.detach(move || {
            let grid = scene.design(&genome, dims);
            let mut cells = Vec::with_capacity(dims.cell_count());
            for x in 0..dims.nx {
                for y in 0..dims.ny {
                    for z in 0..dims.nz {
                        cells.push(grid.get(x, y, z).map_or(-1, |m| i16::from(m.0)));
                    }
                }
            }
            cells
        });
        PyArray1::from_vec(py, cells).reshape([dims.nx, dims.ny, dims.nz])
    }

    /// Evaluates `genome` at `resolution` (`"6x20x6"` or `(6, 20, 6)`): the same bits as
    /// `worker evaluate`. `threads` share the one simulation (the outcome is the same for any
    /// count). The GIL is released meanwhile; Ctrl-C raises KeyboardInterrupt once it ends.
    #[pyo3(signature = (genome, resolution, threads = 1))]
    fn evaluate(
        &self,
        py: Python<'_>,
        genome: &PyGenome,
        resolution: &Bound<'_, PyAny>,
        threads: usize,
    ) -> PyResult<PyOutcome> {
        let dims = self.checked(&genome.inner, resolution)?;
        let pool = evaluation_threads(threads)?;
        let scene = &*self.inner;
        // On this thread, not a helper's as the other long calls: one evaluation cannot be
        // stopped midway anyway, and a thread per call cost a measurable part of a small beam's
        // evaluation (docs/python.md). Ctrl-C raises once the evaluation ends.
        let outcome = py.detach(|| pool.run(|| scene.evaluate(&genome.inner, dims)));
        py.check_signals()?;
        Ok(PyOutcome::new(outcome, scene))
    }

    /// Evaluates every genome at `resolution` on `threads` threads (default: one per core), one
    /// genome per thread at a time; the outcomes come back in order. Ctrl-C stops handing out
    /// genomes and raises KeyboardInterrupt.
    #[pyo3(signature = (genomes, resolution, threads = None))]
    fn evaluate_many(
        &self,
        py: Python<'_>,
        genomes: Vec<PyRef<'_, PyGenome>>,
        resolution: &Bound<'_, PyAny>,
        threads: Option<usize>,
    ) -> PyResult<Vec<PyOutcome>> {
        if genomes.is_empty() {
            return Ok(Vec::new());
        }
        let dims = self.checked_dims(resolution)?;
        for (i, genome) in genomes.iter().enumerate() {
            check_genome(&self.inner, &genome.inner)
                .map_err(|e| PyValueError::new_err(format!("genomes[{i}]: {e}")))?;
        }
        let threads = match threads {
            Some(n) => checked_threads(n)?,
            None => std::thread::available_parallelism().map_or(1, |n| n.get()),
        };
        let genomes: Vec<Genome> = genomes.iter().map(|g| g.inner.clone()).collect();
        let scene = &*self.inner;
        let stop = AtomicBool::new(false);
        let outcomes = interruptible(
            py,
            || stop.store(true, Ordering::Relaxed),
            || evaluate_all(scene, &genomes, dims, threads, &stop),
        )?;
        Ok(outcomes
            .into_iter()
            .map(|o| PyOutcome::new(o, scene))
            .collect())
    }

    /// Writes `genome`'s fabrication files at `resolution` into `folder` (created if missing), as
    /// `worker export` does: STL per material, 3MF, VXA, SVG layers and the task's pictures;
    /// `smooth` meshes the continuous field with about that many samples along the longest side;
    /// `print` adds a voxel-print slice stack. Returns the paths written.
    #[pyo3(signature = (genome, resolution, folder, *, print = false, smooth = None, threads = 1))]
    #[allow(clippy::too_many_arguments)]
    fn export(
        &self,
        py: Python<'_>,
        genome: &PyGenome,
        resolution: &Bound<'_, PyAny>,
        folder: PathBuf,
        print: bool,
        smooth: Option<usize>,
        threads: usize,
    ) -> PyResult<Vec<PathBuf>> {
        let dims = self.checked(&genome.inner, resolution)?;
        let pool = evaluation_threads(threads)?;
        let options = ExportOptions {
            smooth,
            print: print.then(PrintPitch::default),
        };
        let scene = &*self.inner;
        let exported = interruptible(
            py,
            || {},
            || {
                export_design(&genome.inner, scene, dims, &folder, options, || {
                    pool.run(|| scene.evaluate(&genome.inner, dims))
                })
            },
        )?
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok(exported.files)
    }

    /// The scene as a TOML table (what a config's `[scene]` holds).
    fn to_toml(&self) -> PyResult<String> {
        toml::to_string(&*self.inner).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        format!("Scene(kind={:?})", self.inner.kind())
    }
}

impl PyScene {
    /// The resolution, once `genome` is known to fit the scene and the grid the memory budget.
    pub fn checked(
        &self,
        genome: &Genome,
        resolution_arg: &Bound<'_, PyAny>,
    ) -> PyResult<GridDims> {
        let dims = self.checked_dims(resolution_arg)?;
        check_genome(&self.inner, genome)?;
        Ok(dims)
    }

    /// The resolution, once the task can use it and its grid fits the memory budget.
    fn checked_dims(&self, resolution_arg: &Bound<'_, PyAny>) -> PyResult<GridDims> {
        let dims = resolution(resolution_arg)?;
        self.inner
            .check_dims(dims)
            .map_err(|e| PyValueError::new_err(format!("resolution {dims}: {e}")))?;
        amorph::task::memory::check(&self.inner, dims, amorph::task::memory::default_budget())
            .map_err(|e| PyMemoryError::new_err(format!("resolution {dims}: {e}")))?;
        Ok(dims)
    }
}

/// Refuses a genome the scene cannot evaluate (a point outside its limits, an unknown material),
/// naming the point and field.
pub fn check_genome(scene: &Scene, genome: &Genome) -> PyResult<()> {
    genome
        .validate(scene.limits(), scene.palette().len())
        .map_err(|e| PyValueError::new_err(format!("genome: {e}")))
}

/// Evaluates `genomes` on `threads` threads, each taking the next genome when it is free, until
/// `stop`; outcomes in the genomes' order.
fn evaluate_all(
    scene: &Scene,
    genomes: &[Genome],
    dims: GridDims,
    threads: usize,
    stop: &AtomicBool,
) -> Vec<amorph::task::Outcome> {
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, amorph::task::Outcome)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.min(genomes.len()))
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    while !stop.load(Ordering::Relaxed) {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(genome) = genomes.get(i) else { break };
                        mine.push((i, scene.evaluate(genome, dims)));
                    }
                    mine
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_default())
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, o)| o).collect()
}

fn checked_threads(n: usize) -> PyResult<usize> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        Err(PyValueError::new_err(format!(
            "threads = {n} must be between 1 and {MAX_THREADS}"
        )))
    }
}

fn evaluation_threads(n: usize) -> PyResult<EvaluationThreads> {
    let n = checked_threads(n)?;
    EvaluationThreads::new(n, |j| format!("amorph-evaluate-{j}"))
        .map_err(|e| PyOSError::new_err(format!("starting {n} threads: {e}")))
}

/// A validated scene from TOML text; `source` names it in errors.
fn scene(text: &str, at: SceneAt, base: &Path, source: &str) -> PyResult<PyScene> {
    let mut scene = scene_toml::scene_from_toml(text, at)
        .map_err(|e| PyValueError::new_err(format!("{source}: {e}")))?;
    scene
        .load_files(base)
        .map_err(|e| PyValueError::new_err(format!("{source}: scene.{e}")))?;
    scene
        .validate()
        .map_err(|e| PyValueError::new_err(format!("{source}: scene.{e}")))?;
    Ok(PyScene {
        inner: Arc::new(scene),
    })
}
