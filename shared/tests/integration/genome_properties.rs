//! Property tests of the genome and the voxelizer.

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
}

/// Whether coarse cell (x, y, z) lies on a boundary of `grid`: a face neighbour (or the
/// workspace's edge) differs from it in filled state or material.
fn on_boundary(grid: &VoxelGrid, x: usize, y: usize, z: usize) -> bool {
    let here = grid.get(x, y, z);
    amorph::voxel::FACE_OFFSETS.iter().any(|&[dx, dy, dz]| {
        grid.get_signed(x as isize + dx, y as isize + dy, z as isize + dz) != here
    })
}

/// A genome voxelized at twice the resolution and coarsened agrees with the direct voxelization
/// everywhere except on surfaces and material boundaries: the two sample the same continuous
/// field at different points, so they can only disagree where the field crosses the threshold or
/// two materials tie within a coarse cell, which is a boundary of one grid or the other. Checked
/// cell by cell (a disagreement in the interior of both fails). So that an all-empty voxelizer
/// cannot pass, most random genomes must fill something; the filled voxels' overlap (intersection
/// over union, empty cells not counted) is printed for the docs.
#[test]
fn voxelization_is_resolution_consistent() {
    let coarse = GridDims::new(6, 20, 6);
    let fine = GridDims::new(12, 40, 12);
    let mut ious = Vec::new();
    for seed in 0..200 {
        let g = genome(seed, 40);
        let direct = voxelize(&g, coarse, MATERIALS, 0.5);
        let via_fine = coarsen(&voxelize(&g, fine, MATERIALS, 0.5));
        let (mut both, mut either) = (0usize, 0usize);
        for z in 0..coarse.nz {
            for y in 0..coarse.ny {
                for x in 0..coarse.nx {
                    let (a, b) = (direct.get(x, y, z), via_fine.get(x, y, z));
                    both += usize::from(a.is_some() && b.is_some() && a == b);
                    either += usize::from(a.is_some() || b.is_some());
                    let on_edge = on_boundary(&direct, x, y, z) || on_boundary(&via_fine, x, y, z);
                    assert!(
                        a == b || on_edge,
                        "seed {seed}: cell ({x}, {y}, {z}) differs ({a:?} vs {b:?}) inside both grids"
                    );
                }
            }
        }
        if either > 0 {
            ious.push(both as f64 / either as f64);
        }
    }
    let mean = ious.iter().sum::<f64>() / ious.len() as f64;
    let worst = ious.iter().copied().fold(1.0, f64::min);
    println!(
        "resolution consistency (filled IoU): mean {mean:.4}, worst {worst:.4} over {}",
        ious.len()
    );
    assert!(
        ious.len() > 100,
        "most random genomes should fill something"
    );
}
