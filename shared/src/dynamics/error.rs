//! Errors of the dynamics module: malformed input, before any step is taken. A design that
//! diverges while simulating is an outcome ([`super::Divergence`]), not an error.

use crate::material::MaterialError;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DynamicsError {
    #[error("scene field {field} = {value} is out of range")]
    InvalidScene { field: &'static str, value: f64 },
    #[error("palette: {0}")]
    Palette(#[from] MaterialError),
    #[error("voxel material {material} is not in the palette of {palette_len}")]
    UnknownMaterial { material: usize, palette_len: usize },
    #[error("the design has no voxels")]
    Empty,
    #[error("voxel index {index} is out of range for {count} voxels")]
    VoxelIndex { index: usize, count: usize },
}

pub type Result<T> = std::result::Result<T, DynamicsError>;
