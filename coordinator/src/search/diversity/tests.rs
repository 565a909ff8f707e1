use super::*;
use crate::search::fixtures::{island, point_at};
use amorph::material::MaterialId;

#[test]
fn mean_pairwise_distance_averages_every_pair_once() {
    // One-point genomes at 0.1, 0.2, 0.4: pair distances 0.1, 0.3, 0.2.
    let isl = island(0, &[0.1, 0.2, 0.4], &[-1.0, -2.0, -3.0]);
    assert!((mean_pairwise_distance(&isl) - 0.2).abs() < 1e-15);
    assert_eq!(mean_pairwise_distance(&island(0, &[0.3], &[-1.0])), 0.0);
}

#[test]
fn design_distance_is_the_share_of_differing_cells() {
    let dims = GridDims::new(1, 4, 1);
    let soft = Some(MaterialId(0));
    let hard = Some(MaterialId(1));
    let a = VoxelGrid::from_cells(dims, vec![soft, soft, hard, None]);
    let b = VoxelGrid::from_cells(dims, vec![soft, hard, None, None]);
    assert_eq!(design_distance(&a, &a), 0.0);
    assert_eq!(
        design_distance(&a, &b),
        0.5,
        "a material and an emptiness differ"
    );
    assert_eq!(design_distance(&a, &b), design_distance(&b, &a));
}

/// The log's incremental measurement equals a fresh [`measure`] after every change: a
/// replaced individual, several epochs with none, and a change of resolution.
#[test]
fn the_cached_measurement_is_the_fresh_one_as_individuals_change() {
    let scene: Scene =
        toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").expect("a beam");
    let dir = std::env::temp_dir().join(format!("amorph-diversity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let mut log = DiversityLog::create(&dir).expect("diversity.csv");
    // Points dense and wide enough to reach the clamp, so that the designs differ too.
    let blob = |x: f64| {
        let mut genome = point_at(x);
        let p = &mut genome.points[0];
        (p.position, p.density, p.falloff) = ([0.5, 0.3 * x, 0.5], 1.0, 0.5);
        genome
    };
    let mut islands = vec![
        island(0, &[0.1, 0.2, 0.4, 0.7], &[-1.0, -2.0, -3.0, -4.0]),
        island(1, &[0.3, 0.5, 0.9], &[-0.5, -2.0, -1.0]),
    ];
    for ind in islands.iter_mut().flat_map(|i| &mut i.population) {
        ind.genome = blob(ind.genome.points[0].position[0]);
    }
    let (coarse, fine) = (GridDims::new(6, 20, 6), GridDims::new(12, 40, 12));
    let mut designs_differ = false;
    for (epoch, dims) in [coarse, coarse, coarse, fine, fine, fine]
        .into_iter()
        .enumerate()
    {
        if epoch % 2 == 1 {
            islands[epoch % 2].population[epoch % 3].genome = blob(0.05 + 0.1 * epoch as f64);
        }
        let fresh = measure(&islands, &scene, dims);
        designs_differ |= fresh.iter().any(|d| d.design_pairwise > 0.0);
        assert_eq!(log.measure(&islands, &scene, dims), fresh, "epoch {epoch}");
    }
    assert!(
        designs_differ,
        "the designs must differ for the test to mean anything"
    );
    std::fs::remove_dir_all(&dir).ok();
}
