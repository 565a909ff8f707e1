//! Property test: on random small multi-material designs, every solver's displacements satisfy
//! K u = f for the SI stiffness assembled independently from the public triplets.

use amorph::material::{Material, MaterialId, Palette};
use amorph::statics::{StaticLoadCase, StaticModel, StaticSolverParams, solve};
use amorph::voxel::{GridDims, VoxelGrid, keep_connected_to_base};
use proptest::prelude::*;

/// ‖K u − f‖ / ‖f‖ over the free DOF, in SI units, with K summed from the triplets.
fn residual(model: &StaticModel, case: &StaticLoadCase, u: &[[f64; 6]]) -> f64 {
    let n = model.node_count();
    let mut fixed = vec![false; n];
    for &f in &case.fixed_nodes {
        fixed[f] = true;
    }
    let mut r = vec![0.0; 6 * n];
    for &(node, load) in &case.loads {
        for (c, l) in load.iter().enumerate() {
            r[6 * node + c] += l;
        }
    }
    for (row, col, v) in model.stiffness_triplets() {
        r[row] -= v * u[col / 6][col % 6];
    }
    let norm = |v: &[f64]| {
        v.chunks_exact(6)
            .enumerate()
            .filter(|(node, _)| !fixed[*node])
            .flat_map(|(_, c)| c.iter().map(|x| x * x))
            .sum::<f64>()
            .sqrt()
    };
    let mut f = vec![0.0; 6 * n];
    for &(node, load) in &case.loads {
        for (c, l) in load.iter().enumerate() {
            f[6 * node + c] += l;
        }
    }
    norm(&r) / norm(&f)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every solver meets K u = f to its tolerance 1e-9 (the residual is measured here with an
    /// independent SI assembly, so 1e-9 plus round-off: 2e-9).
    #[test]
    #[ignore = "issue 2: fails at 1e6 contrast, open"]
    fn solve_reproduces_k_u_equals_f(
        cells in prop::collection::vec(0u8..4, 4 * 6 * 3),
        contrast in prop::sample::select(vec![1.0, 1.0e3, 1.0e6]),
        load in prop::array::uniform6(-1.0f64..1.0),
    ) {
        let dims = GridDims::new(4, 6, 3);
        // 0 empty, 1–2 hard, 3 soft: three quarters filled on average
        let raw = cells
            .iter()
            .map(|&c| match c {
                0 => None,
                3 => Some(MaterialId(1)),
                _ => Some(MaterialId(0)),
            })
            .collect();
        let grid = keep_connected_to_base(&VoxelGrid::from_cells(dims, raw));
        prop_assume!(grid.filled_count() > 0);
        let palette = Palette(vec![
            Material::new("hard", 1.0e9, 0.35),
            Material::new("soft", 1.0e9 / contrast, 0.45),
        ]);
        let model = StaticModel::new(&grid, &palette, 1.0e-3).unwrap();
        let fixed_nodes: Vec<usize> =
            (0..model.node_count()).filter(|&n| model.node_coords(n)[1] == 0).collect();
        let last = model.node_count() - 1;
        prop_assume!(model.node_coords(last)[1] > 0);
        let moment = |v: f64| v * 1.0e-3;
        let case = StaticLoadCase {
            fixed_nodes,
            loads: vec![(last, [load[0], load[1], load[2], moment(load[3]), moment(load[4]), moment(load[5])])],
        };
        for mut params in [StaticSolverParams::direct(), StaticSolverParams::multigrid_pcg()] {
            params.multigrid.coarse_max_nodes = 4;
            let solution = solve(&model, &case, &params).unwrap();
            let r = residual(&model, &case, &solution.displacements);
            prop_assert!(r < 2e-9, "{:?}: residual {r:e}", solution.diagnostics);
        }
    }
}
