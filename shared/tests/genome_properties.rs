//! Property tests of the genome and the voxelizer (issue 2).

use amorph::genome::{
    CutPlane, DominantParent, Genome, GenomeLimits, MutationParams, crossover, mutate,
    random_genome,
};
use amorph::voxel::{GridDims, VoxelGrid, voxelize};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const MATERIALS: usize = 2;

fn genome(seed: u64, points: usize) -> Genome {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    random_genome(&mut rng, points, &GenomeLimits::default(), MATERIALS)
}

/// Coarsens a grid by 2 along every axis: a coarse voxel is filled where at least half of its eight
/// children are, with their most common material.
fn coarsen(fine: &VoxelGrid) -> VoxelGrid {
    let f = fine.dims();
    let dims = GridDims::new(f.nx / 2, f.ny / 2, f.nz / 2);
    let mut out = VoxelGrid::empty(dims);
    for z in 0..dims.nz {
        for y in 0..dims.ny {
            for x in 0..dims.nx {
                let mut counts = [0usize; MATERIALS];
                for (dx, dy, dz) in (0..8).map(|k| (k & 1, (k >> 1) & 1, k >> 2)) {
                    if let Some(m) = fine.get(2 * x + dx, 2 * y + dy, 2 * z + dz) {
                        counts[m.index()] += 1;
                    }
                }
                if counts.iter().sum::<usize>() >= 4 {
                    let m = (0..MATERIALS)
                        .max_by_key(|&k| (counts[k], std::cmp::Reverse(k)))
                        .unwrap();
                    out.set(x, y, z, Some(amorph::material::MaterialId(m as u8)));
                }
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn json_round_trip_is_lossless(seed in any::<u64>(), points in 0usize..60) {
        let g = genome(seed, points);
        let text = serde_json::to_string(&g).unwrap();
        let back: Genome = serde_json::from_str(&text).unwrap();
        prop_assert_eq!(back, g);
    }

    #[test]
    fn crossover_takes_every_child_point_from_exactly_one_side_of_one_parent(
        seed in any::<u64>(), na in 0usize..40, nb in 0usize..40,
    ) {
        let (a, b) = (genome(seed, na), genome(seed ^ 0x9e37, nb));
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let plane = CutPlane::random(&mut rng);
        let c = crossover(&a, &b, &plane, 1000);
        let front_a: Vec<_> = a.points.iter().filter(|p| plane.is_front(p.position)).copied().collect();
        let back_b: Vec<_> = b.points.iter().filter(|p| !plane.is_front(p.position)).copied().collect();
        prop_assert_eq!(&c.child.points[..c.from_parents.0], &front_a[..]);
        prop_assert_eq!(&c.child.points[c.from_parents.0..], &back_b[..]);
        prop_assert_eq!(c.child.len(), front_a.len() + back_b.len());
        let expected = if front_a.len() >= back_b.len() { DominantParent::A } else { DominantParent::B };
        prop_assert_eq!(c.dominant, expected);
    }

    #[test]
    fn crossover_respects_the_point_limit(seed in any::<u64>()) {
        let (a, b) = (genome(seed, 30), genome(seed + 1, 30));
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let c = crossover(&a, &b, &CutPlane::random(&mut rng), 10);
        prop_assert!(c.child.len() <= 10);
        prop_assert_eq!(c.from_parents.0 + c.from_parents.1, c.child.len());
    }

    #[test]
    fn mutation_keeps_every_value_in_range(seed in any::<u64>(), points in 1usize..50, step in 0.01f64..2.0) {
        let limits = GenomeLimits::default();
        let params = MutationParams { step, add_point: 0.5, remove_point: 0.5, ..Default::default() };
        let mut g = genome(seed, points);
        let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_add(7));
        for _ in 0..20 {
            mutate(&mut g, &mut rng, &params, &limits, MATERIALS);
            prop_assert!(g.validate(&limits, MATERIALS).is_ok(), "{:?}", g.validate(&limits, MATERIALS));
            prop_assert!(g.len() >= limits.min_points);
        }
    }

    #[test]
    fn voxelizing_twice_gives_identical_grids(seed in any::<u64>()) {
        let g = genome(seed, 40);
        let dims = GridDims::new(6, 20, 6);
        prop_assert_eq!(voxelize(&g, dims, MATERIALS, 0.5), voxelize(&g, dims, MATERIALS, 0.5));
    }
}

/// A genome voxelized at twice the resolution and coarsened agrees with the direct voxelization on
/// most voxels. Disagreements can only sit where the density crosses the threshold or two materials
/// tie within a voxel, i.e. on surfaces and material boundaries; over 200 random 40-point genomes
/// at 6x20x6 vs 12x40x12 we measured a mean agreement of 99.30 % and a worst case of 96.67 %
/// (coarse cells; the fine grid votes by majority of its 8 children), so the bounds below
/// (mean ≥ 98.5 %, every genome ≥ 95 %) leave room only for that boundary effect.
#[test]
fn voxelization_is_resolution_consistent() {
    let coarse = GridDims::new(6, 20, 6);
    let fine = GridDims::new(12, 40, 12);
    let mut agreements = Vec::new();
    for seed in 0..200 {
        let g = genome(seed, 40);
        let direct = voxelize(&g, coarse, MATERIALS, 0.5);
        let via_fine = coarsen(&voxelize(&g, fine, MATERIALS, 0.5));
        let same = direct
            .cells()
            .iter()
            .zip(via_fine.cells())
            .filter(|(a, b)| a == b)
            .count();
        agreements.push(same as f64 / coarse.cell_count() as f64);
    }
    let mean = agreements.iter().sum::<f64>() / agreements.len() as f64;
    let worst = agreements.iter().copied().fold(1.0, f64::min);
    println!("resolution consistency: mean {mean:.4}, worst {worst:.4}");
    assert!(mean >= 0.985, "mean agreement {mean}");
    assert!(worst >= 0.95, "worst agreement {worst}");
}
