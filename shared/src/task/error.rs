//! The one error a scene's validation gives: which field, and what is wrong with it.

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
    dims: crate::voxel::GridDims,
) -> Result<(), String> {
    let cells = dims.cell_count();
    if voxels == 0 || voxels > cells {
        return Err(format!("voxels = {voxels} outside 1..={cells}"));
    }
    if material_counts.len() != materials || material_counts.iter().sum::<usize>() != voxels {
        return Err(format!(
            "material_counts {material_counts:?} do not add up to voxels = {voxels} over {materials} materials"
        ));
    }
    Ok(())
}
