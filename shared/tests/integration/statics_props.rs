//! Property test: on random small multi-material designs, every solver's displacements satisfy
//! K u = f for the SI stiffness assembled independently from the public triplets.

use amorph::material::{Material, MaterialId, Palette};
use amorph::statics::{StaticLoadCase, StaticModel, StaticSolverParams, solve};
use amorph::voxel::{GridDims, VoxelGrid, keep_connected_to_base};
use proptest::prelude::*;

/// ‖K u − f‖ / ‖f‖ over the free DOF, in SI units, with K summed from the triplets, and the
/// double-precision floor of that measurement, 64 eps ‖|K| |u|‖ / ‖f‖. The floor bounds two errors
/// that no solver can remove: rounding the solution to doubles (|K δu| ≤ eps |K| |u|) and the
/// plain summation of this check (γ_n |K| |u| with n ≤ 42 terms per row; Higham, ch. 3). At
/// 1e6:1 contrast ‖|K||u|‖/‖f‖ reaches ~1e8, so the floor is then above the 1e-9 tolerance.
fn residual(model: &StaticModel, case: &StaticLoadCase, u: &[[f64; 6]]) -> (f64, f64) {
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
    let mut magnitude = vec![0.0; 6 * n];
    for (row, col, v) in model.stiffness_triplets() {
        r[row] -= v * u[col / 6][col % 6];
        magnitude[row] += (v * u[col / 6][col % 6]).abs();
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
    (
        norm(&r) / norm(&f),
        64.0 * f64::EPSILON * norm(&magnitude) / norm(&f),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Every solver meets K u = f to its tolerance 1e-9 (the residual is measured here with an
    /// independent SI assembly, so 1e-9 plus round-off: 2e-9, plus the double-precision floor of
    /// the returned displacements, see `residual`). The solvers' own diagnostics, computed on the
    /// unrounded solution with compensated sums, must meet 1e-9 outright.
    #[test]
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
            let (r, floor) = residual(&model, &case, &solution.displacements);
            prop_assert!(solution.diagnostics.relative_residual <= 1e-9, "{:?}", solution.diagnostics);
            prop_assert!(
                r < 2e-9 + floor,
                "{:?}: residual {r:e}, floor {floor:e}",
                solution.diagnostics
            );
        }
    }
}
