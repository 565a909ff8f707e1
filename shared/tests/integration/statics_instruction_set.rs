//! A solution is the same bits on every CPU: the solver's loops run compiled for AVX2 where the
//! CPU has it and for baseline x86-64 where it does not (`statics::baseline_only` forces the
//! latter), and both must compute every value by the same operations in the same order. On a
//! CPU without AVX2 both runs take the baseline loops and this test compares a path with itself.

use amorph::material::{Material, MaterialId, Palette};
use amorph::statics::{
    SolveMethodUsed, StaticLoadCase, StaticModel, StaticSolution, StaticSolverParams,
    baseline_only, solve,
};
use amorph::voxel::{GridDims, VoxelGrid};

/// Hard resin with soft voxels scattered through it at the contrast `ratio` (the beams' 1000:1,
/// and 10⁶:1, where the compensated refinement takes more than one step).
fn two_material(dims: GridDims, ratio: f64) -> (VoxelGrid, Palette) {
    let mut grid = VoxelGrid::filled(dims, MaterialId(0));
    for i in 0..dims.cell_count() {
        let [x, y, z] = dims.coords(i);
        if (x + 2 * y + 3 * z) % 3 == 0 {
            grid.set(x, y, z, Some(MaterialId(1)));
        }
    }
    let palette = Palette(vec![
        Material::new("hard", 1.0e9, 0.35),
        Material::new("soft", 1.0e9 / ratio, 0.45),
    ]);
    (grid, palette)
}

/// The y = 0 layer clamped, the last layer pushed down and twisted.
fn cantilever(model: &StaticModel) -> StaticLoadCase {
    let ny = model.dims().ny;
    let layer = |y: usize| (0..model.node_count()).filter(move |&n| model.node_coords(n)[1] == y);
    StaticLoadCase {
        fixed_nodes: layer(0).collect(),
        loads: layer(ny - 1)
            .map(|n| (n, [0.0, 0.0, -1.0e-3, 1.0e-7, 0.0, 0.0]))
            .collect(),
    }
}

fn bits(solution: &StaticSolution) -> Vec<u64> {
    let diagnostics = &solution.diagnostics;
    (solution.displacements.iter().flatten())
        .map(|v| v.to_bits())
        .chain([
            diagnostics.iterations as u64,
            diagnostics.relative_residual.to_bits(),
        ])
        .collect()
}

#[test]
fn solver_bits_do_not_depend_on_the_instruction_set() {
    let mut small_hierarchy = StaticSolverParams::multigrid_pcg();
    small_hierarchy.multigrid.coarse_max_nodes = 20;
    let cases = [
        // the beams' own case: 12x40x12 at 1000:1 on the default solver (multigrid PCG)
        (
            GridDims::new(12, 40, 12),
            1.0e3,
            StaticSolverParams::default(),
        ),
        (GridDims::new(4, 20, 4), 1.0e6, small_hierarchy),
        (
            GridDims::new(4, 20, 4),
            1.0e6,
            StaticSolverParams::block_jacobi_pcg(),
        ),
        (GridDims::new(4, 20, 4), 1.0e6, StaticSolverParams::direct()),
    ];
    for (dims, ratio, params) in cases {
        let (grid, palette) = two_material(dims, ratio);
        let model = StaticModel::new(&grid, &palette, 1.0e-3).unwrap();
        let case = cantilever(&model);
        let wide = solve(&model, &case, &params).unwrap();
        let baseline = baseline_only(|| solve(&model, &case, &params)).unwrap();
        let label = format!("{dims:?} at {ratio:e}:1, {:?}", wide.diagnostics);
        assert!(wide.diagnostics.relative_residual <= 1e-9, "{label}");
        if dims.nx == 12 {
            assert_eq!(wide.diagnostics.method, SolveMethodUsed::PcgMultigrid);
        }
        assert_eq!(
            wide.diagnostics, baseline.diagnostics,
            "{label}: the baseline loops' diagnostics differ"
        );
        assert!(
            bits(&wide) == bits(&baseline),
            "{label}: the baseline loops' displacements differ in their bits"
        );
    }
}
