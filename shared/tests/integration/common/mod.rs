//! Helpers shared by the integration tests (each test file includes this module).

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
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
