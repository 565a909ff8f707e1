//! Accuracy of the static solver against analytic beam theory, a dense reference solve,
//! linearity and symmetry, plus its typed errors.

use amorph::material::{Material, MaterialId, Palette};
use amorph::statics::{
    SolveMethodUsed, SolverMethod, StaticLoadCase, StaticModel, StaticSolverParams, StaticsError,
    solve,
};
use amorph::voxel::{GridDims, VoxelGrid};
use nalgebra::{DMatrix, DVector};

use crate::common::{cantilever_case, contrast_palette, two_material_design};

const VOXEL: f64 = 1.0e-3;

fn single_material(e: f64, nu: f64) -> Palette {
    Palette(vec![Material::new("m", e, nu)])
}

/// Mean downward deflection of the tip layer.
fn tip_deflection(model: &StaticModel, displacements: &[[f64; 6]]) -> f64 {
    let ny = model.dims().ny;
    let tip: Vec<f64> = (0..model.node_count())
        .filter(|&n| model.node_coords(n)[1] == ny - 1)
        .map(|n| -displacements[n][2])
        .collect();
    tip.iter().sum::<f64>() / tip.len() as f64
}

/// A slender 2×40×2 cantilever matches Euler–Bernoulli F L³ / (3 E I). The lattice's section of
/// four chains joined by cross links has exactly the continuum I = (2s)⁴/12 (Steiner terms 4·s²·(s/2)²
/// plus four own s⁴/12), so the only departure is the lattice's shear flexibility, of relative size
/// ~(h/L)² ≈ 0.3 % here; hence the 0.5 % bound.
#[test]
fn slender_beam_matches_euler_bernoulli() {
    let e = 1.0e9;
    let dims = GridDims::new(2, 40, 2);
    let grid = VoxelGrid::filled(dims, MaterialId(0));
    let model = StaticModel::new(&grid, &single_material(e, 0.35), VOXEL).unwrap();
    let force = 1.0e-2;
    let case = StaticLoadCase::cantilever(&model, force);
    let solution = solve(&model, &case, &StaticSolverParams::direct()).unwrap();
    let length = 39.0 * VOXEL;
    let inertia = (2.0 * VOXEL).powi(4) / 12.0;
    let analytic = force * length.powi(3) / (3.0 * e * inertia);
    let computed = tip_deflection(&model, &solution.displacements);
    let error = (computed - analytic).abs() / analytic;
    println!(
        "slender 2x40x2: computed {computed:e} m, Euler-Bernoulli {analytic:e} m, error {:+.3} %",
        100.0 * (computed - analytic) / analytic
    );
    assert!(
        error < 5e-3,
        "computed {computed:e} analytic {analytic:e} error {:.3} %",
        100.0 * error
    );
}

/// A stocky 12×40×12 cantilever deflects more than Euler–Bernoulli (shear adds compliance) and
/// at most as much as Timoshenko with κ = 5/6 plus a margin: the lattice's shear stiffness comes
/// from the bending of its links, so it is bounded by the continuum's shear behaviour only
/// approximately. The bounds are the physics, the 5 % margin on Timoshenko covers the lattice's
/// lack of Poisson coupling (it behaves as ν = 0 laterally).
#[test]
fn stocky_beam_lies_between_euler_bernoulli_and_timoshenko() {
    let (e, nu) = (1.0e9, 0.35);
    let dims = GridDims::new(12, 40, 12);
    let grid = VoxelGrid::filled(dims, MaterialId(0));
    let model = StaticModel::new(&grid, &single_material(e, nu), VOXEL).unwrap();
    let force = 1.0e-2;
    let case = StaticLoadCase::cantilever(&model, force);
    let solution = solve(&model, &case, &StaticSolverParams::default()).unwrap();
    let length = 39.0 * VOXEL;
    let side = 12.0 * VOXEL;
    let inertia = side.powi(4) / 12.0;
    let area = side * side;
    let shear_modulus = e / (2.0 * (1.0 + nu));
    let euler_bernoulli = force * length.powi(3) / (3.0 * e * inertia);
    let timoshenko = euler_bernoulli + force * length / (5.0 / 6.0 * shear_modulus * area);
    let computed = tip_deflection(&model, &solution.displacements);
    eprintln!("EB {euler_bernoulli:e} computed {computed:e} Timoshenko {timoshenko:e}");
    assert!(
        computed > euler_bernoulli && computed < 1.05 * timoshenko,
        "EB {euler_bernoulli:e} computed {computed:e} Timoshenko {timoshenko:e}"
    );
}

/// A small two-material design with a hole, as a dense SI system: K from the public triplets,
/// fixed DOF removed, solved by nalgebra's dense Cholesky.
fn dense_reference(model: &StaticModel, case: &StaticLoadCase) -> Vec<[f64; 6]> {
    let n = model.node_count();
    let mut fixed = vec![false; n];
    for &f in &case.fixed_nodes {
        fixed[f] = true;
    }
    let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
    let mut index = vec![usize::MAX; n];
    for (k, &node) in free.iter().enumerate() {
        index[node] = k;
    }
    let dof = 6 * free.len();
    let mut k = DMatrix::<f64>::zeros(dof, dof);
    for (r, c, v) in model.stiffness_triplets() {
        let (rn, cn) = (r / 6, c / 6);
        if fixed[rn] || fixed[cn] {
            continue;
        }
        k[(6 * index[rn] + r % 6, 6 * index[cn] + c % 6)] += v;
    }
    let mut f = DVector::<f64>::zeros(dof);
    for &(node, load) in &case.loads {
        if !fixed[node] {
            for (c, l) in load.iter().enumerate() {
                f[6 * index[node] + c] += l;
            }
        }
    }
    let u = k.cholesky().expect("reduced K is SPD").solve(&f);
    let mut out = vec![[0.0; 6]; n];
    for (kk, &node) in free.iter().enumerate() {
        out[node] = std::array::from_fn(|c| u[6 * kk + c]);
    }
    out
}

/// Relative max-norm difference of displacement fields, translations and rotations separately
/// (their units differ).
fn relative_difference(a: &[[f64; 6]], b: &[[f64; 6]]) -> f64 {
    let mut worst: f64 = 0.0;
    for part in [0..3, 3..6] {
        let scale = b
            .iter()
            .flat_map(|u| u[part.clone()].iter().map(|v| v.abs()))
            .fold(0.0, f64::max);
        let diff = a
            .iter()
            .zip(b)
            .flat_map(|(u, v)| part.clone().map(move |k| (u[k] - v[k]).abs()))
            .fold(0.0, f64::max);
        worst = worst.max(diff / scale);
    }
    worst
}

/// Direct and both PCG variants agree with an independent dense Cholesky of the SI system to
/// 1e-9 relative: round-off of a condition number ~1e6 system is ~1e-10, and PCG runs to a
/// 1e-11 residual here so its error is well below the bound.
#[test]
fn sparse_solves_equal_dense_solve() {
    let dims = GridDims::new(3, 6, 3);
    let grid = two_material_design(dims, 4, true);
    let model = StaticModel::new(&grid, &contrast_palette(1000.0), VOXEL).unwrap();
    let mut case = cantilever_case(&model);
    // a moment and an axial force too, so every DOF kind is exercised
    case.loads.push((
        model.node_count() - 1,
        [1e-3, -2e-3, 0.0, 1e-6, -3e-6, 2e-6],
    ));
    let reference = dense_reference(&model, &case);
    for mut params in [
        StaticSolverParams::direct(),
        StaticSolverParams::multigrid_pcg(),
        StaticSolverParams::block_jacobi_pcg(),
    ] {
        params.tolerance = 1e-11;
        params.multigrid.coarse_max_nodes = 4; // force a real hierarchy on this small grid
        let solution = solve(&model, &case, &params).unwrap();
        let diff = relative_difference(&solution.displacements, &reference);
        assert!(
            diff < 1e-9,
            "{:?}: relative difference {diff:e}",
            solution.diagnostics
        );
    }
}

/// The true residual reaches 1e-9 at stiffness contrasts of 1000:1 and 1e6:1, with the direct
/// solver and with multigrid PCG (the acceptance bound).
#[test]
fn two_material_residual_meets_tolerance() {
    let dims = GridDims::new(4, 20, 4);
    for ratio in [1.0e3, 1.0e6] {
        let grid = two_material_design(dims, 3, false);
        let model = StaticModel::new(&grid, &contrast_palette(ratio), VOXEL).unwrap();
        let case = cantilever_case(&model);
        for mut params in [
            StaticSolverParams::direct(),
            StaticSolverParams::multigrid_pcg(),
        ] {
            params.multigrid.coarse_max_nodes = 20;
            let solution = solve(&model, &case, &params).unwrap();
            let d = &solution.diagnostics;
            assert!(d.relative_residual <= 1e-9, "ratio {ratio:e}: {d:?}");
            if params.method == SolverMethod::Pcg {
                assert_eq!(d.method, SolveMethodUsed::PcgMultigrid);
            }
        }
    }
}

/// Doubling the load doubles every displacement (a linear solver; 1e-12 covers round-off).
#[test]
fn response_is_linear_in_the_load() {
    let dims = GridDims::new(3, 10, 3);
    let grid = two_material_design(dims, 5, true);
    let model = StaticModel::new(&grid, &contrast_palette(1000.0), VOXEL).unwrap();
    let one = solve(
        &model,
        &StaticLoadCase::cantilever(&model, 1.0),
        &StaticSolverParams::direct(),
    )
    .unwrap();
    let two = solve(
        &model,
        &StaticLoadCase::cantilever(&model, 2.0),
        &StaticSolverParams::direct(),
    )
    .unwrap();
    let halved: Vec<[f64; 6]> = two
        .displacements
        .iter()
        .map(|u| u.map(|v| v / 2.0))
        .collect();
    assert!(relative_difference(&halved, &one.displacements) < 1e-12);
}

/// A design mirror-symmetric in X under a symmetric load responds symmetrically: u_y, u_z and θx
/// are even in x, u_x, θy and θz odd. The solver sees a different node order on each side, so
/// agreement to 1e-9 relative (PCG tolerance) tests assembly and solve.
#[test]
fn mirror_symmetric_design_deflects_symmetrically() {
    let dims = GridDims::new(5, 12, 3);
    let mut grid = VoxelGrid::filled(dims, MaterialId(0));
    for y in 0..dims.ny {
        for z in 0..dims.nz {
            if (y + z) % 3 == 0 {
                grid.set(0, y, z, Some(MaterialId(1)));
                grid.set(4, y, z, Some(MaterialId(1)));
            }
        }
    }
    grid.set(2, 6, 1, None);
    let model = StaticModel::new(&grid, &contrast_palette(1000.0), VOXEL).unwrap();
    let case = cantilever_case(&model);
    for params in [
        StaticSolverParams::direct(),
        StaticSolverParams::multigrid_pcg(),
    ] {
        let u = solve(&model, &case, &params).unwrap().displacements;
        let mut mirrored = vec![[0.0; 6]; u.len()];
        for (node, slot) in mirrored.iter_mut().enumerate() {
            let [x, y, z] = model.node_coords(node);
            let twin = model
                .node_of_cell(dims.index(dims.nx - 1 - x, y, z))
                .unwrap();
            let v = u[twin];
            *slot = [-v[0], v[1], v[2], v[3], -v[4], -v[5]];
        }
        let diff = relative_difference(&mirrored, &u);
        assert!(diff < 1e-8, "{diff:e}");
    }
}

#[test]
fn empty_design_is_a_typed_error() {
    let grid = VoxelGrid::empty(GridDims::new(2, 2, 2));
    let err = StaticModel::new(&grid, &single_material(1e9, 0.3), VOXEL).unwrap_err();
    assert_eq!(err, StaticsError::EmptyModel);
}

#[test]
fn missing_support_is_a_typed_error() {
    let grid = VoxelGrid::filled(GridDims::new(2, 3, 2), MaterialId(0));
    let model = StaticModel::new(&grid, &single_material(1e9, 0.3), VOXEL).unwrap();
    let mut case = cantilever_case(&model);
    case.fixed_nodes.clear();
    let err = solve(&model, &case, &StaticSolverParams::default()).unwrap_err();
    assert_eq!(err, StaticsError::NoFixedNode);
}

#[test]
fn floating_part_is_a_typed_error() {
    let dims = GridDims::new(3, 6, 1);
    let mut grid = VoxelGrid::filled(dims, MaterialId(0));
    for x in 0..3 {
        grid.set(x, 3, 0, None); // cut the beam in two
    }
    let model = StaticModel::new(&grid, &single_material(1e9, 0.3), VOXEL).unwrap();
    let case = cantilever_case(&model);
    let err = solve(&model, &case, &StaticSolverParams::default()).unwrap_err();
    assert_eq!(err, StaticsError::Unconnected { count: 6, first: 9 });
}

#[test]
fn non_finite_load_is_a_typed_error() {
    let grid = VoxelGrid::filled(GridDims::new(1, 3, 1), MaterialId(0));
    let model = StaticModel::new(&grid, &single_material(1e9, 0.3), VOXEL).unwrap();
    let case = StaticLoadCase {
        fixed_nodes: vec![0],
        loads: vec![(2, [0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0])],
    };
    let err = solve(&model, &case, &StaticSolverParams::default()).unwrap_err();
    assert!(
        matches!(
            err,
            StaticsError::NonFiniteLoad {
                node: 2,
                component: 1,
                ..
            }
        ),
        "{err}"
    );
}

/// Block-Jacobi PCG given too few iterations reports non-convergence with its residual.
#[test]
fn non_convergence_is_a_typed_error() {
    let grid = VoxelGrid::filled(GridDims::new(2, 20, 2), MaterialId(0));
    let model = StaticModel::new(&grid, &single_material(1e9, 0.3), VOXEL).unwrap();
    let case = cantilever_case(&model);
    let params = StaticSolverParams {
        max_iterations: 5,
        ..StaticSolverParams::block_jacobi_pcg()
    };
    let err = solve(&model, &case, &params).unwrap_err();
    match err {
        StaticsError::NotConverged {
            iterations,
            residual,
            ..
        } => {
            assert_eq!(iterations, 5);
            assert!(residual > 1e-9);
        }
        other => panic!("expected NotConverged, got {other}"),
    }
}
