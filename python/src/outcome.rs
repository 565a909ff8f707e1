//! `amorph.Outcome` and `amorph.Failure`: what an evaluation returns, as Python objects.

use amorph::dynamics::DivergenceReason;
use amorph::outcome::Failure;
use amorph::task::{Outcome, Scene};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::json_to_py;

/// One evaluation's result: a fitness with the task's metrics, or a failure saying why not.
#[pyclass(name = "Outcome", module = "amorph", frozen)]
#[derive(Clone, Debug)]
pub struct PyOutcome {
    pub inner: Outcome,
    /// The task's figure (a beam's RMS error in %, a robot's speed), if evaluated.
    figure: Option<f64>,
    headline: Option<String>,
}

impl PyOutcome {
    pub fn new(inner: Outcome, scene: &Scene) -> Self {
        Self {
            figure: scene.figure(&inner),
            headline: scene.headline(&inner),
            inner,
        }
    }
}

#[pymethods]
impl PyOutcome {
    /// Whether the design was evaluated (it has a fitness).
    #[getter]
    fn ok(&self) -> bool {
        self.inner.fitness().is_some()
    }

    /// The fitness the search maximizes, or None for a failure.
    #[getter]
    fn fitness(&self) -> Option<f64> {
        self.inner.fitness()
    }

    /// The task's headline figure: a beam's RMS error in %, a robot's speed, a stiffness task's
    /// compliance; None for a failure.
    #[getter]
    fn figure(&self) -> Option<f64> {
        self.figure
    }

    /// The task's measurements as a dict, or None for a failure.
    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(metrics) = self.inner.metrics() else {
            return Ok(None);
        };
        let value =
            serde_json::to_value(metrics).map_err(|e| PyValueError::new_err(e.to_string()))?;
        // Metrics are tagged by task (`{"beam": {...}}`); the caller knows its task.
        let inner = match value {
            serde_json::Value::Object(map) if map.len() == 1 => {
                map.into_iter().next().map(|(_, v)| v).unwrap_or_default()
            }
            other => other,
        };
        json_to_py(py, &inner).map(Some)
    }

    /// Why the design has no fitness, or None.
    #[getter]
    fn failure(&self) -> Option<PyFailure> {
        match &self.inner {
            Outcome::Failed { failure } => Some(PyFailure::from(failure)),
            Outcome::Evaluated { .. } => None,
        }
    }

    /// An outcome from the project's JSON (`worker evaluate`'s output, a run store's column),
    /// judged by `scene`'s task for its figure.
    #[staticmethod]
    fn from_json(text: &str, scene: &crate::scene::PyScene) -> PyResult<Self> {
        let inner: Outcome = serde_json::from_str(text)
            .map_err(|e| PyValueError::new_err(format!("outcome JSON: {e}")))?;
        Ok(Self::new(inner, &scene.inner))
    }

    /// The outcome as the project's JSON (what `worker evaluate` prints).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The outcome as a dict: `{"fitness", "figure", "metrics"}` or `{"failure": {...}}`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        dict.set_item("fitness", self.fitness())?;
        dict.set_item("figure", self.figure)?;
        dict.set_item("metrics", self.metrics(py)?)?;
        dict.set_item(
            "failure",
            self.failure().map(|f| f.to_dict(py)).transpose()?,
        )?;
        Ok(dict)
    }

    /// Equal when both evaluations gave the same bits.
    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        match (&self.inner, &self.headline) {
            (Outcome::Evaluated { fitness, .. }, Some(h)) => {
                format!("Outcome(fitness={fitness}, {h})")
            }
            (Outcome::Evaluated { fitness, .. }, None) => format!("Outcome(fitness={fitness})"),
            (Outcome::Failed { failure }, _) => format!("Outcome(failed: {failure})"),
        }
    }
}

/// Why an evaluation gave no fitness. `kind` is one of `invalid_genome`, `invalid_request`,
/// `empty`, `not_spanning`, `solver`, `degenerate`, `internal`, `diverged`.
#[pyclass(name = "Failure", module = "amorph", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct PyFailure {
    #[pyo3(get)]
    kind: &'static str,
    /// The whole reason, as the run store and the report give it.
    #[pyo3(get)]
    message: String,
    /// For `diverged`: the simulated time, s, at which the simulation diverged.
    #[pyo3(get)]
    time: Option<f64>,
    reason: Option<DivergenceReason>,
}

impl From<&Failure> for PyFailure {
    fn from(failure: &Failure) -> Self {
        let kind = match failure {
            Failure::InvalidGenome(_) => "invalid_genome",
            Failure::InvalidRequest(_) => "invalid_request",
            Failure::Empty => "empty",
            Failure::NotSpanning => "not_spanning",
            Failure::Solver(_) => "solver",
            Failure::Degenerate(_) => "degenerate",
            Failure::Internal(_) => "internal",
            Failure::Diverged { .. } => "diverged",
        };
        let (time, reason) = match failure {
            Failure::Diverged { time, reason } => (Some(*time), Some(reason.clone())),
            _ => (None, None),
        };
        Self {
            kind,
            message: failure.to_string(),
            time,
            reason,
        }
    }
}

#[pymethods]
impl PyFailure {
    /// For `diverged`: what crossed its limit, as a dict: `{"kind": "non_finite"}`,
    /// `{"kind": "strain", "strain": ..., "limit": ...}` or
    /// `{"kind": "runaway", "travel": ..., "limit": ...}` (travel in voxel sizes per step).
    #[getter]
    fn reason<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.reason
            .as_ref()
            .map(|r| json_to_py(py, &serde_json::to_value(r).expect("a reason serializes")))
            .transpose()
    }

    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        dict.set_item("kind", self.kind)?;
        dict.set_item("message", &self.message)?;
        dict.set_item("time", self.time)?;
        dict.set_item("reason", self.reason(py)?)?;
        Ok(dict)
    }

    fn __repr__(&self) -> String {
        format!("Failure({}: {})", self.kind, self.message)
    }
}
