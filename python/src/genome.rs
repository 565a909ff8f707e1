//! `amorph.Genome`: a design as the project's JSON or as an (N, 6) array of point parameters.

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// The array columns, in order.
pub const COLUMNS: [&str; 6] = ["x", "y", "z", "density", "falloff", "material"];

/// A design: Gaussian points, each adding its signed density to its material's field.
#[pyclass(name = "Genome", module = "amorph", frozen, eq)]
#[derive(Clone, Debug, PartialEq)]
pub struct PyGenome {
    pub inner: Genome,
}

#[pymethods]
impl PyGenome {
    /// A genome from an (N, 6) array-like of points: x, y, z (workspace units, [0, 1]),
    /// density, falloff, material (a whole number).
    #[new]
    fn new(points: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::from_array_like(points)
    }

    /// A genome from an (N, 6) array-like: columns x, y, z, density, falloff, material.
    #[staticmethod]
    fn from_array(points: &Bound<'_, PyAny>) -> PyResult<Self> {
        Self::from_array_like(points)
    }

    /// The (N, 6) float64 array of the points: x, y, z, density, falloff, material.
    fn to_array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = self
            .inner
            .points
            .iter()
            .map(|p| {
                vec![
                    p.position[0],
                    p.position[1],
                    p.position[2],
                    p.density,
                    p.falloff,
                    f64::from(p.material.0),
                ]
            })
            .collect();
        if rows.is_empty() {
            return Ok(numpy::PyArray2::zeros(py, [0, COLUMNS.len()], false));
        }
        PyArray2::from_vec2(py, &rows).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// A genome from the project's JSON: a bare genome (`{"points": [...]}`) or a results file
    /// holding one under `genome` (`best_genome.json`).
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        amorph_worker::parse_genome(text, "genome JSON")
            .map(|inner| Self { inner })
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The genome as the project's JSON (what `worker evaluate --genome` reads).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(&self.inner).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// A genome from a JSON file (a genome, or a results file such as `best_genome.json`).
    #[staticmethod]
    fn load(path: std::path::PathBuf) -> PyResult<Self> {
        amorph_worker::read_genome(&path)
            .map(|inner| Self { inner })
            .map_err(|e| match e {
                amorph_worker::WorkerError::Read { .. } => PyOSError::new_err(format!("{e}")),
                _ => PyValueError::new_err(e.to_string()),
            })
    }

    /// Writes the genome's JSON to `path`.
    fn save(&self, path: std::path::PathBuf) -> PyResult<()> {
        std::fs::write(&path, self.to_json()?)
            .map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!("Genome({} points)", self.inner.len())
    }
}

impl PyGenome {
    /// An (N, 6) array-like as a genome, refusing a wrong shape, a non-finite value or a
    /// material that is not a whole number from 0 to 255.
    pub fn from_array_like(points: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = points.py();
        let array = py
            .import("numpy")?
            .call_method1("ascontiguousarray", (points, "float64"))
            .map_err(|e| PyValueError::new_err(format!("genome array: {e}")))?;
        let Ok(array) = array.cast::<PyArray2<f64>>() else {
            let ndim: usize = array.getattr("ndim")?.extract()?;
            return Err(PyValueError::new_err(format!(
                "genome array: expected 2 dimensions (N points × 6 columns), got {ndim}"
            )));
        };
        let shape = array.shape();
        if shape[1] != COLUMNS.len() {
            return Err(PyValueError::new_err(format!(
                "genome array: expected 6 columns ({}), got shape ({}, {})",
                COLUMNS.join(", "),
                shape[0],
                shape[1]
            )));
        }
        let readonly = array.readonly();
        let values = readonly
            .as_slice()
            .map_err(|e| PyValueError::new_err(format!("genome array: {e}")))?;
        let points = values
            .chunks_exact(COLUMNS.len())
            .enumerate()
            .map(|(i, row)| point(i, row))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Self {
            inner: Genome::new(points),
        })
    }
}

/// One array row as a point, refusing what no scene could use.
fn point(i: usize, row: &[f64]) -> PyResult<GaussianPoint> {
    for (value, column) in row.iter().zip(COLUMNS) {
        if !value.is_finite() {
            return Err(PyValueError::new_err(format!(
                "genome array: point {i}, {column} = {value} is not finite"
            )));
        }
    }
    let material = row[5];
    if material.fract() != 0.0 || !(0.0..=255.0).contains(&material) {
        return Err(PyValueError::new_err(format!(
            "genome array: point {i}, material = {material} is not a material index (a whole number 0 to 255)"
        )));
    }
    Ok(GaussianPoint {
        position: [row[0], row[1], row[2]],
        density: row[3],
        falloff: row[4],
        material: MaterialId(material as u8),
    })
}
