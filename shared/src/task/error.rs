//! The errors of a task's checks: a scene field that cannot be used ([`SceneError`]), a
//! resolution the task cannot use ([`ResolutionError`]), and a peer's outcome the scene cannot
//! have produced ([`ImplausibleClaim`]).

use crate::voxel::GridDims;

/// A scene field that cannot be used, named by its path in the config (`dynamics.settle.max_time`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct SceneError {
    pub field: String,
    pub problem: String,
}

impl SceneError {
    pub fn new(field: impl Into<String>, problem: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            problem: problem.into(),
        }
    }

    /// The same error under an enclosing field: `settle.max_time` within `dynamics` becomes
    /// `dynamics.settle.max_time`.
    pub fn within(self, parent: &str) -> Self {
        Self {
            field: format!("{parent}.{}", self.field),
            problem: self.problem,
        }
    }
}

/// Why a task cannot be evaluated at a resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ResolutionError {
    #[error("a cantilever needs at least 2 layers along y, got {0}")]
    TooFewLayers(GridDims),
    /// A cantilever runs along y: 12x12x40 would be a 12-voxel beam 40 voxels deep, almost surely
    /// a slip for the paper's 12x40x12.
    #[error(
        "a cantilever runs along y, so ny must be its longest count (did you mean [{}, {}, {}]?)",
        .0.nx, .0.nz, .0.ny
    )]
    NotAlongY(GridDims),
}

/// A peer's outcome that the scene cannot have produced at the task's resolution; the text names
/// the figure and what is wrong with it (`surface_voxels = 500 exceeds the 480 columns`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ImplausibleClaim(pub String);

/// An [`ImplausibleClaim`] from `format!` arguments.
macro_rules! implausible {
    ($($arg:tt)*) => {
        $crate::task::error::ImplausibleClaim(format!($($arg)*))
    };
}
pub(crate) use implausible;

/// Checks that `value` is finite and positive, naming `field` if not.
pub fn positive(field: &str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SceneError::new(
            field,
            format!("{value} must be a positive number"),
        ))
    }
}

/// Checks that `value` is finite, naming `field` if not.
pub fn finite(field: &str, value: f64) -> Result<(), SceneError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SceneError::new(
            field,
            format!("{value} must be a finite number"),
        ))
    }
}

/// Checks a peer's voxel counts against the grid: 1 to `dims.cell_count()` voxels, one count per
/// palette material, adding up to the total.
pub fn counts_fit(
    voxels: usize,
    material_counts: &[usize],
    materials: usize,
    dims: GridDims,
) -> Result<(), ImplausibleClaim> {
    let cells = dims.cell_count();
    if voxels == 0 || voxels > cells {
        return Err(implausible!("voxels = {voxels} outside 1..={cells}"));
    }
    if material_counts.len() != materials || material_counts.iter().sum::<usize>() != voxels {
        return Err(implausible!(
            "material_counts {material_counts:?} do not add up to voxels = {voxels} over {materials} materials"
        ));
    }
    Ok(())
}
