//! Amorph from Python (`import amorph`): genomes as numpy arrays, scenes, evaluation on threads
//! without the GIL, whole runs heard epoch by epoch, run stores read as columns, and a coordinator
//! that evaluates the batches of any Python optimizer on its workers. The Python side
//! (`python/amorph/`) wraps this module, `amorph._amorph`.

mod cluster;
mod convert;
mod genome;
mod interrupt;
mod outcome;
mod runs;
mod scene;
mod store;

use pyo3::prelude::*;

#[pymodule]
fn _amorph(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<genome::PyGenome>()?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<outcome::PyOutcome>()?;
    m.add_class::<outcome::PyFailure>()?;
    m.add_class::<runs::PyRunHandle>()?;
    m.add_class::<cluster::PyCluster>()?;
    m.add_function(wrap_pyfunction!(store::read_run_store, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("GENOME_COLUMNS", genome::COLUMNS.to_vec())?;
    Ok(())
}
