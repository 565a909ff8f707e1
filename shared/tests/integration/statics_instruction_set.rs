//! A solution is the same bits on every CPU: the solver's loops run compiled for AVX2 where the
//! CPU has it and for baseline x86-64 where it does not (`statics::baseline_only` forces the
//! latter), and both must compute every value by the same operations in the same order. On a
//! CPU without AVX2 both runs take the baseline loops and this test compares a path with itself.

use amorph::statics::{
    SolveMethodUsed, StaticModel, StaticSolution, StaticSolverParams, baseline_only, solve,
};
use amorph::voxel::GridDims;

use crate::common::{cantilever_case, contrast_palette, two_material_design};

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
        // soft voxels scattered through hard resin, the tip pushed down and twisted
        let grid = two_material_design(dims, 3, false);
        let model = StaticModel::new(&grid, &contrast_palette(ratio), 1.0e-3).unwrap();
        let mut case = cantilever_case(&model);
        case.loads.iter_mut().for_each(|(_, load)| load[3] = 1.0e-7);
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
