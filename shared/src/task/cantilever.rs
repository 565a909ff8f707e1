//! The cantilever load case the static tasks share: the design's voxels at the `y = 0` layer are
//! clamped, the free-end layer `y = ny − 1` carries a total downward (−Z) force spread evenly over
//! its voxels, and the statics give every voxel's displacement.

use crate::material::Palette;
use crate::outcome::Failure;
use crate::statics::{self, StaticLoadCase, StaticModel, StaticSolution, StaticSolverParams};
use crate::task::SceneError;
use crate::task::error::ResolutionError;
use crate::task::error::{finite, positive};
use crate::voxel::{GridDims, VoxelGrid};

/// The cantilever runs along y (clamped at y = 0, loaded at the last layer, deflecting in −z), so
/// it needs two layers and y must be its longest count.
pub fn check_cantilever_dims(dims: GridDims) -> Result<(), ResolutionError> {
    if dims.ny < 2 {
        return Err(ResolutionError::TooFewLayers(dims));
    }
    if dims.ny < dims.nx || dims.ny < dims.nz {
        return Err(ResolutionError::NotAlongY(dims));
    }
    Ok(())
}

/// Checks the load case's own fields of a scene, naming the bad one.
pub fn check_load_case(
    length: f64,
    tip_load: f64,
    solver: &StaticSolverParams,
    threshold: f64,
) -> Result<(), SceneError> {
    positive("length", length)?;
    positive("tip_load", tip_load)?;
    solver
        .validate()
        .map_err(|e| SceneError::new("solver", e.to_string()))?;
    finite("threshold", threshold)
}

/// A solved cantilever: the model (for node look-ups) and its solution.
#[derive(Debug)]
pub struct SolvedCantilever {
    model: StaticModel,
    pub solution: StaticSolution,
}

impl SolvedCantilever {
    /// Displacement and rotation of the voxel at grid cell `cell` (it must be filled).
    pub fn displacement(&self, cell: usize) -> [f64; 6] {
        let node = self
            .model
            .node_of_cell(cell)
            .expect("a filled cell of the solved design has a node");
        self.solution.displacements[node]
    }
}

/// Flat indices of the filled cells of layer `y`, in (z, x) order.
pub fn layer_cells(grid: &VoxelGrid, y: usize) -> impl Iterator<Item = usize> + '_ {
    let dims = grid.dims();
    (0..dims.nz)
        .flat_map(move |z| (0..dims.nx).map(move |x| (x, z)))
        .filter(move |&(x, z)| grid.get(x, y, z).is_some())
        .map(move |(x, z)| dims.index(x, y, z))
}

/// Clamps the root layer, loads the tip layer with `tip_load` N downward, and solves. An empty
/// design, one that does not reach the tip layer, or a solver failure is a [`Failure`].
pub fn solve_cantilever(
    grid: &VoxelGrid,
    palette: &Palette,
    voxel_size: f64,
    tip_load: f64,
    solver: &StaticSolverParams,
) -> Result<SolvedCantilever, Failure> {
    let dims = grid.dims();
    if grid.filled_count() == 0 {
        return Err(Failure::Empty);
    }
    if layer_cells(grid, dims.ny - 1).next().is_none() {
        return Err(Failure::NotSpanning);
    }
    let model =
        StaticModel::new(grid, palette, voxel_size).map_err(|e| Failure::Solver(e.to_string()))?;
    let case = StaticLoadCase::cantilever(&model, tip_load);
    let solution =
        statics::solve(&model, &case, solver).map_err(|e| Failure::Solver(e.to_string()))?;
    Ok(SolvedCantilever { model, solution })
}
