//! Static solver benchmarks, single thread. Sizes are in the names; two-material designs are full
//! boxes whose hard/soft (1000:1) pattern is a seeded random Gaussian-mixture genome.
//!
//! `cargo bench -p amorph --bench statics -- --warm-up-time 1 --measurement-time 3`
//!
//! A method named `..._baseline_loops` is the same solve on the loops a CPU without AVX2 runs
//! (`statics::baseline_only`), measured right after the wide loops' run of it.

use std::hint::black_box;

use amorph::genome::{GenomeLimits, random_genome};
use amorph::material::{MaterialId, Palette};
use amorph::statics::{StaticLoadCase, StaticModel, StaticSolverParams, baseline_only, solve};
use amorph::voxel::{GridDims, VoxelGrid, voxelize};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const BEAM_LENGTH: f64 = 0.04;

fn homogeneous(dims: GridDims) -> VoxelGrid {
    VoxelGrid::filled(dims, MaterialId(0))
}

/// Every cell filled, the material chosen by a seeded random genome of 24 points. Densities are
/// made positive so both materials win regions (with signed densities a seed can leave one
/// material nowhere on top, and the "two-material" case would silently be homogeneous).
fn two_material(dims: GridDims, seed: u64) -> VoxelGrid {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut genome = random_genome(&mut rng, 24, &GenomeLimits::default(), 2);
    genome
        .points
        .iter_mut()
        .for_each(|p| p.density = p.density.abs());
    let grid = voxelize(&genome, dims, 2, f64::NEG_INFINITY);
    let counts = grid.material_counts(2);
    eprintln!(
        "two-material {dims}: {} hard, {} soft voxels",
        counts[0], counts[1]
    );
    assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
    grid
}

fn bench_case(
    c: &mut Criterion,
    name: &str,
    grid: &VoxelGrid,
    methods: &[(&str, StaticSolverParams)],
) {
    let dims = grid.dims();
    let palette = Palette::hard_soft_resins();
    let model = StaticModel::new(grid, &palette, BEAM_LENGTH / dims.ny as f64).unwrap();
    let case = StaticLoadCase::cantilever(&model, 0.01);
    for (method, params) in methods {
        let run = || {
            let solve = || solve(black_box(&model), black_box(&case), params).unwrap();
            if method.ends_with("_baseline_loops") {
                baseline_only(solve)
            } else {
                solve()
            }
        };
        let start = std::time::Instant::now();
        let solution = run();
        eprintln!(
            "{name}_{method}: first solve {:.3} s, {:?}",
            start.elapsed().as_secs_f64(),
            solution.diagnostics
        );
        c.bench_function(&format!("{name}_{method}"), |b| b.iter(run));
    }
}

fn statics(c: &mut Criterion) {
    let direct = ("direct", StaticSolverParams::direct());
    let multigrid = ("multigrid", StaticSolverParams::multigrid_pcg());
    let jacobi = ("block_jacobi", StaticSolverParams::block_jacobi_pcg());
    let multigrid_baseline = (
        "multigrid_baseline_loops",
        StaticSolverParams::multigrid_pcg(),
    );

    let grid = two_material(GridDims::new(12, 40, 12), 7);
    c.bench_function("static_model_build_12x40x12", |b| {
        b.iter(|| StaticModel::new(black_box(&grid), &Palette::hard_soft_resins(), 1e-3).unwrap())
    });

    bench_case(
        c,
        "static_solve_6x20x6",
        &two_material(GridDims::new(6, 20, 6), 7),
        &[direct.clone(), multigrid.clone(), jacobi.clone()],
    );
    bench_case(
        c,
        "static_solve_12x40x12_homogeneous",
        &homogeneous(GridDims::new(12, 40, 12)),
        &[direct.clone(), multigrid.clone()],
    );
    bench_case(
        c,
        "static_solve_12x40x12_two_material",
        &two_material(GridDims::new(12, 40, 12), 7),
        &[
            direct.clone(),
            multigrid.clone(),
            multigrid_baseline,
            jacobi,
        ],
    );
    if std::env::var_os("AMORPH_BENCH_LARGE").is_some() {
        bench_case(
            c,
            "static_solve_24x80x24_two_material",
            &two_material(GridDims::new(24, 80, 24), 7),
            &[multigrid],
        );
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = statics
}
criterion_main!(benches);
