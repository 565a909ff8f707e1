//! Voxels: the grid a genome is discretised into, voxelization, and connected components.

mod components;
mod grid;
mod voxelize;

pub use components::{
    face_neighbours, keep_connected_to_base, keep_largest_component, label_components,
};
pub use grid::{FACE_OFFSETS, GridDims, VoxelGrid};
pub use voxelize::{DEFAULT_THRESHOLD, LayerSampler, density_fields, material_at, voxelize};
