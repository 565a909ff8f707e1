//! Fabrication exports of a design (paper §III-D and §IV-C): closed per-material surface meshes as
//! binary STL for multi-material printing, VXA for VoxCAD/Voxelyze, and SVG laser-cut layers.

pub mod layers;
pub mod mesh;
pub mod stl;
pub mod vxa;

pub use layers::{Contour, alignment_holes_mm, layer_contours, layer_svg};
pub use mesh::{TriangleMesh, boundary_mesh};
pub use stl::{read_binary_stl, write_binary_stl};
pub use vxa::{VxaDesign, VxaError, read_vxa, write_vxa};

use crate::material::MaterialId;
use crate::voxel::VoxelGrid;

/// The closed surface of each material's voxels, in millimetres (index = material id); a material
/// with no voxels gets an empty mesh.
pub fn material_meshes_mm(
    grid: &VoxelGrid,
    material_count: usize,
    voxel_size: f64,
) -> Vec<TriangleMesh> {
    (0..material_count)
        .map(|m| {
            let id = MaterialId(m as u8);
            boundary_mesh(grid, voxel_size, |cell| cell == Some(id)).scaled(1e3)
        })
        .collect()
}
