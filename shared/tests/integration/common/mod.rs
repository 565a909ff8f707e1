//! Helpers shared by the integration tests (each test file includes this module).

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::{Material, MaterialId, Palette};
use amorph::statics::{StaticLoadCase, StaticModel};
use amorph::task::locomotion::LocomotionScene;
use amorph::voxel::{GridDims, VoxelGrid};

/// A grid from one byte per cell: 0 empty, k the material k − 1.
#[allow(dead_code)] // not every test file that includes this module builds grids by hand
pub fn grid_from(dims: GridDims, cells: &[u8]) -> VoxelGrid {
    VoxelGrid::from_cells(
        dims,
        cells
            .iter()
            .map(|&c| (c > 0).then(|| MaterialId(c - 1)))
            .collect(),
    )
}

/// A short walk of a two-material 6×6×6 body: passive at −x, actuated at +x, three 0.02 s cycles
/// after at most 0.02 s of settling, so a test takes well under a second: enough motion for
/// pictures and for different starts, not a gait.
#[allow(dead_code)] // not every test file that includes this module walks
pub fn short_walker() -> (Genome, LocomotionScene, GridDims) {
    let blob = |x: f64, material: u8| GaussianPoint {
        position: [x, 0.5, 0.3],
        density: 1.0,
        falloff: 0.2,
        material: MaterialId(material),
    };
    let genome = Genome::new(vec![blob(0.3, 0), blob(0.7, 1)]);
    let mut scene = LocomotionScene {
        workspace: 0.008,
        ..LocomotionScene::default()
    };
    scene.actuation_cycles = 3;
    scene.settle.max_time = 0.02;
    if let Some(a) = scene.dynamics.actuation.as_mut() {
        a.period = 0.02;
    }
    (genome, scene, GridDims::new(6, 6, 6))
}

/// The library's cantilever with a total tip force of 0.01 N.
pub fn cantilever_case(model: &StaticModel) -> StaticLoadCase {
    StaticLoadCase::cantilever(model, 1.0e-2)
}

/// Hard resin with soft voxels where (x + 2y + 3z) is a multiple of `soft_every`, and optionally
/// one voxel removed from the middle.
pub fn two_material_design(dims: GridDims, soft_every: usize, hole: bool) -> VoxelGrid {
    let mut grid = VoxelGrid::filled(dims, MaterialId(0));
    for i in 0..dims.cell_count() {
        let [x, y, z] = dims.coords(i);
        if (x + 2 * y + 3 * z) % soft_every == 0 {
            grid.set(x, y, z, Some(MaterialId(1)));
        }
    }
    if hole {
        grid.set(1, dims.ny / 2, 1, None);
    }
    grid
}

/// Hard resin (1 GPa) and a soft one `ratio` times softer.
pub fn contrast_palette(ratio: f64) -> Palette {
    Palette(vec![
        Material::new("hard", 1.0e9, 0.35),
        Material::new("soft", 1.0e9 / ratio, 0.45),
    ])
}
