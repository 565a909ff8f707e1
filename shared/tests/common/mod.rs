//! Helpers shared by the integration tests (each test file includes this module).

use amorph::material::MaterialId;
use amorph::voxel::{GridDims, VoxelGrid};

/// A grid from one byte per cell: 0 empty, k the material k − 1.
pub fn grid_from(dims: GridDims, cells: &[u8]) -> VoxelGrid {
    VoxelGrid::from_cells(
        dims,
        cells
            .iter()
            .map(|&c| (c > 0).then(|| MaterialId(c - 1)))
            .collect(),
    )
}
