//! Fabrication exports of a design (paper §III-D and §IV-C): closed per-material surface meshes as
//! binary STL and a multi-material 3MF for printing, VXA for VoxCAD/Voxelyze, and SVG laser-cut layers.

pub mod layers;
mod merge;
pub mod mesh;
pub mod print;
pub mod scaling;
pub mod smooth;
pub mod stl;
pub mod threemf;
pub mod voxcraft;
pub mod vxa;

pub use layers::{Contour, alignment_holes_mm, layer_contours, layer_svg};
pub use mesh::{TriangleMesh, boundary_mesh};
pub use print::{PrintError, PrintPitch, Slicer, write_slice_stack};
pub use scaling::{PhysicalBuild, dynamic_actuation_force, equivalent_actuation_period};
pub use smooth::{SampledField, isosurface, samples_per_voxel, smooth_material_meshes};
pub use stl::{read_binary_stl, write_binary_stl};
pub use threemf::{package_3mf, write_3mf};
pub use voxcraft::{write_voxcraft_base, write_vxd};
pub use vxa::{VxaDesign, VxaError, read_vxa, write_vxa};

use crate::material::MaterialId;
use crate::report::render_isometric;
use crate::voxel::VoxelGrid;

/// The closed surface of each material's voxels, in millimetres (index = material id), with
/// coplanar faces merged into rectangles (no T-junctions; see `merge`); a material with no voxels
/// gets an empty mesh.
pub fn material_meshes_mm(
    grid: &VoxelGrid,
    material_count: usize,
    voxel_size: f64,
) -> Vec<TriangleMesh> {
    (0..material_count)
        .map(|m| {
            let id = MaterialId(m as u8);
            let surface = mesh::boundary_surface(grid, voxel_size, |cell| cell == Some(id));
            merge::merged_mesh(&surface).scaled(1e3)
        })
        .collect()
}

/// Writes every fabrication file of a design into `dir`: `material-<i>-<name>.stl` per material
/// present, `design.3mf` (all materials), `design.vxa` (with the scene's simulation settings: a
/// robot's protocol, a beam's load case; with the design's `outcome`, its own measured settle),
/// for a robot voxcraft-sim's pair `voxcraft/base.vxa` (the task's settings, shared by every
/// design) and `voxcraft/design.vxd`, and `layers/layer-<z>.svg` per voxel layer. Returns the
/// files written, relative to `dir`.
pub fn write_fabrication_files(
    dir: &std::path::Path,
    grid: &VoxelGrid,
    scene: &crate::task::Scene,
    outcome: Option<&crate::task::Outcome>,
) -> std::io::Result<Vec<std::path::PathBuf>> {
    use std::path::PathBuf;
    let palette = scene.palette();
    let voxel_size = scene.voxel_size(grid.dims());
    std::fs::create_dir_all(dir.join("layers"))?;
    let mut written = Vec::new();
    let meshes = material_meshes_mm(grid, palette.len(), voxel_size);
    for (m, mesh) in meshes.iter().enumerate() {
        if mesh.triangles.is_empty() {
            continue;
        }
        let name = PathBuf::from(format!(
            "material-{m}-{}.stl",
            file_safe(&palette.0[m].name)
        ));
        let mut file = std::io::BufWriter::new(std::fs::File::create(dir.join(&name))?);
        write_binary_stl(mesh, &format!("amorph material {m}"), &mut file)?;
        std::io::Write::flush(&mut file)?;
        written.push(name);
    }
    let settings = scene.simulator_settings(grid.dims(), outcome);
    // Our simulation lowers a body onto its floor; the simulators that read these files drop it
    // from where its grid puts it, so a body whose lowest voxels sit three layers up fell 6 mm,
    // tumbled and walked the other way there (docs/how-to/voxelyze.md). They get the body on the
    // floor.
    let simulated = VxaDesign {
        grid: match &settings {
            Some(s) if s.scene.floor.is_some() => resting_on_floor(grid),
            _ => grid.clone(),
        },
        palette: palette.clone(),
        voxel_size,
    };
    let vxa = write_vxa(&simulated, settings.as_ref());
    std::fs::write(dir.join("design.vxa"), vxa)?;
    written.push(PathBuf::from("design.vxa"));
    // voxcraft-sim's pair for a robot only: the load case's relaxation has not been checked there.
    let shared = scene.simulator_settings(grid.dims(), None);
    if let Some(shared) = shared.as_ref().filter(|s| s.load_case.is_none()) {
        std::fs::create_dir_all(dir.join("voxcraft"))?;
        for (name, text) in [
            (
                "voxcraft/base.vxa",
                write_voxcraft_base(palette, voxel_size, shared),
            ),
            ("voxcraft/design.vxd", write_vxd(&simulated.grid)),
        ] {
            std::fs::write(dir.join(name), text)?;
            written.push(PathBuf::from(name));
        }
    }
    let package = package_3mf(&meshes, palette).map_err(std::io::Error::other)?;
    std::fs::write(dir.join("design.3mf"), package)?;
    written.push(PathBuf::from("design.3mf"));
    let picture = render_isometric(grid, palette, 12.0)
        .to_png()
        .map_err(std::io::Error::other)?;
    std::fs::write(dir.join("design.png"), picture)?;
    written.push(PathBuf::from("design.png"));
    for z in 0..grid.dims().nz {
        let name = PathBuf::from(format!("layers/layer-{:03}.svg", z + 1));
        std::fs::write(dir.join(&name), layer_svg(grid, palette, voxel_size, z))?;
        written.push(name);
    }
    Ok(written)
}

/// Writes `material-<i>-<name>-smooth.stl` per material present: the smooth surface of the
/// genome's field (see [`smooth_material_meshes`]) sampled about `samples_longest` times along the
/// design's longest side, in mm in the frame of the voxel STL files. Returns the files written,
/// relative to `dir`.
pub fn write_smooth_surfaces(
    dir: &std::path::Path,
    genome: &crate::genome::Genome,
    scene: &crate::task::Scene,
    dims: crate::voxel::GridDims,
    samples_longest: usize,
) -> std::io::Result<Vec<std::path::PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let per_voxel = samples_per_voxel(dims, samples_longest);
    let meshes = smooth_material_meshes(genome, scene, dims, per_voxel);
    let mut written = Vec::new();
    for (m, mesh) in meshes.iter().enumerate() {
        if mesh.triangles.is_empty() {
            continue;
        }
        let name = std::path::PathBuf::from(format!(
            "material-{m}-{}-smooth.stl",
            file_safe(&scene.palette().0[m].name)
        ));
        let mut file = std::io::BufWriter::new(std::fs::File::create(dir.join(&name))?);
        write_binary_stl(
            mesh,
            &format!("amorph material {m}, smooth, {per_voxel} samples per voxel"),
            &mut file,
        )?;
        std::io::Write::flush(&mut file)?;
        written.push(name);
    }
    Ok(written)
}

/// Text as XML character data or as an attribute value in double quotes.
pub(crate) fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}

/// `grid` without the empty layers below its lowest voxel: the body as it rests on a floor at
/// z = 0, which is where our simulation puts it before it settles. Same x and y extent, so a
/// voxel keeps its x and y cell; an empty grid comes back unchanged.
pub fn resting_on_floor(grid: &VoxelGrid) -> VoxelGrid {
    let d = grid.dims();
    let plane = d.nx * d.ny;
    let Some(lowest) = grid.filled_indices().map(|i| i / plane).min() else {
        return grid.clone();
    };
    let dims = crate::voxel::GridDims::new(d.nx, d.ny, d.nz - lowest);
    VoxelGrid::from_cells(dims, grid.cells()[lowest * plane..].to_vec())
}
