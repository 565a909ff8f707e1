use super::*;
use amorph::genome::{GenomeLimits, random_genome};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn beam() -> Scene {
    toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").expect("a beam scene")
}

/// Every accepted insertion adds one narrow point at a voxel of the design's boundary and gives
/// that voxel the state it aimed at in the voxelization, whatever the design: the density comes
/// from the field there, so this holds for any genome and cell.
#[test]
fn an_insertion_gives_its_voxel_a_new_state_and_changes_little_else() {
    let scene = beam();
    let dims = GridDims::new(6, 20, 6);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut inserted, mut changed_cells) = (0, Vec::new());
    for _ in 0..40 {
        let genome = random_genome(&mut rng, 30, &GenomeLimits::default(), 2);
        let site = BoundarySite::new(&genome, &scene, dims);
        let raw = |g: &Genome| amorph::voxel::voxelize(g, dims, 2, scene.threshold());
        let before = raw(&genome);
        let mut child = genome.clone();
        let Some((cell, state)) = site.insert(&mut child, &mut rng, &scene) else {
            assert_eq!(child, genome, "a refused insertion leaves the genome alone");
            continue;
        };
        inserted += 1;
        assert_eq!(child.len(), genome.len() + 1);
        child
            .validate(scene.limits(), 2)
            .expect("within the limits");
        assert!(
            site.boundary.contains(&cell),
            "cell {cell} is on the boundary"
        );
        assert_ne!(
            site.design.cells()[cell],
            state,
            "a new state for its voxel"
        );
        let p = child.points.last().expect("the new point");
        assert_eq!(
            p.falloff,
            scene.limits().falloff[0],
            "the narrowest falloff"
        );
        let after = raw(&child);
        let [x, y, z] = dims.coords(cell);
        assert_eq!(
            p.position,
            dims.normalized_centre(x, y, z),
            "on its voxel's centre"
        );
        assert_eq!(
            after.cells()[cell],
            state,
            "its voxel took the state aimed at"
        );
        let changed = (0..dims.cell_count())
            .filter(|&i| after.cells()[i] != before.cells()[i])
            .count();
        changed_cells.push(changed);
    }
    // A random genome's field can lie further from the threshold than one point's density
    // reaches (30 wide Gaussians add up); those changes are refused above. Enough must remain
    // for the assertions on them to mean something.
    assert!(
        inserted >= 10,
        "only {inserted} of 40 insertions were possible"
    );
    changed_cells.sort_unstable();
    // A Gaussian of the narrowest falloff reaches its 26 neighbours at under half its peak,
    // so a median change beyond the 3x3x3 block would mean the density is far from minimal.
    assert!(
        changed_cells[changed_cells.len() / 2] <= 27,
        "{changed_cells:?}"
    );
}
