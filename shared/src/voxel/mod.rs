//! Voxels: the grid a genome is discretised into, voxelization, and connected components.

mod components;
mod grid;
mod voxelize;

pub use components::{
    face_neighbours, keep_connected_to_base, keep_largest_component, label_components,
};
pub use grid::{FACE_OFFSETS, GridDims, MAX_AXIS_VOXELS, MAX_VOXELS, VoxelGrid};
pub use voxelize::{
    DEFAULT_THRESHOLD, LayerSampler, centre_weight, check_lattice, density_fields, material_at,
    voxel_densities, voxelize, voxelize_averaged,
};
