//! Voxelization speed: 100 random Gaussian points into the paper's beam workspace and into a fine grid.

use amorph::genome::{GenomeLimits, random_genome};
use amorph::voxel::{GridDims, voxelize};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn voxelize_100_points(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(100);
    let genome = random_genome(&mut rng, 100, &GenomeLimits::default(), 2);
    for (name, dims) in [
        ("voxelize_100_points_12x40x12", GridDims::new(12, 40, 12)),
        ("voxelize_100_points_64x200x64", GridDims::new(64, 200, 64)),
    ] {
        c.bench_function(name, |b| b.iter(|| voxelize(&genome, dims, 2, 0.5)));
    }
}

criterion_group!(benches, voxelize_100_points);
criterion_main!(benches);
