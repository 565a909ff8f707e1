use super::*;
use amorph::genome::{GenomeLimits, random_genome};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn beam() -> Scene {
    toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").expect("a beam scene")
}

/// An evolved circular-arc design (session 37's climb start), a beam with a boundary.
fn evolved_genome() -> Genome {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/data/climb/arc_8x6_s15_first_fine_epoch.json"
    );
    let design: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("the design file"))
            .expect("design JSON");
    serde_json::from_value(design["genome"].clone()).expect("a genome")
}

/// Guided by the beam's flip model, a site draws only changes the model expects to help, each
/// aimed at its voxel; where the outcome is another resolution's, the site is unguided and
/// draws exactly as a plain site does.
#[test]
fn guided_insertions_go_where_the_model_expects_a_gain() {
    let scene = beam();
    let dims = GridDims::new(6, 20, 6);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let genome = evolved_genome();
    let outcome = scene.evaluate(&genome, dims);
    assert!(outcome.fitness().is_some(), "{outcome:?}");
    let design = scene.design(&genome, dims);
    let model = scene.flip_model(&design, &outcome).expect("a beam's model");
    let site = BoundarySite::new(&genome, &scene, dims).guided_by(&scene, &outcome);
    let guided = site
        .guided_changes()
        .expect("some change is expected to help");
    let all = site.boundary.len() * 2;
    assert!(guided < all, "{guided} of {all} changes expected to help");
    let mut inserted = 0;
    for _ in 0..200 {
        let mut child = genome.clone();
        if let Some((cell, to)) = site.insert(&mut child, &mut rng, &scene) {
            assert!(model.gain(cell, to) > 0.0, "cell {cell} to {to:?}");
            inserted += 1;
        }
    }
    assert!(inserted >= 100, "{inserted} of 200 insertions possible");

    let coarse = scene.evaluate(&genome, GridDims::new(4, 12, 4));
    let unguided = BoundarySite::new(&genome, &scene, dims).guided_by(&scene, &coarse);
    assert_eq!(unguided.guided_changes(), None);
    let plain = BoundarySite::new(&genome, &scene, dims);
    let (mut a, mut b) = (ChaCha8Rng::seed_from_u64(9), ChaCha8Rng::seed_from_u64(9));
    for _ in 0..50 {
        let (mut x, mut y) = (genome.clone(), genome.clone());
        assert_eq!(
            unguided.insert(&mut x, &mut a, &scene),
            plain.insert(&mut y, &mut b, &scene)
        );
        assert_eq!(x, y);
    }
}

/// The model step's sequence changes each voxel once, each change expected to help given the
/// ones before it (replayed on a fresh model), and its children are the best with the first
/// 1, 2, 4, ... changes appended as points, each aimed at its voxel.
#[test]
fn a_model_step_takes_changes_that_help_given_the_ones_before() {
    let scene = beam();
    let dims = GridDims::new(6, 20, 6);
    let genome = evolved_genome();
    let outcome = scene.evaluate(&genome, dims);
    let site =
        BoundarySite::new(&genome, &scene, dims).with_model_step(&genome, &scene, &outcome, 8);
    assert_eq!(site.sequence.len(), 8, "eight changes expected to help");
    let mut model = scene
        .flip_model(&site.design, &outcome)
        .expect("a beam's model");
    let mut cells: Vec<usize> = Vec::new();
    for &(cell, to) in &site.sequence {
        assert!(model.gain(cell, to) > 0.0, "cell {cell} to {to:?}");
        model.take(cell, to);
        assert!(!cells.contains(&cell), "cell {cell} changed twice");
        cells.push(cell);
    }
    let children = site.model_step_children(&genome, &scene, 5);
    let lengths: Vec<usize> = children.iter().map(|c| c.len() - genome.len()).collect();
    assert_eq!(lengths, [1, 2, 4, 8], "no child past the sequence's length");
    for child in &children {
        assert_eq!(child.points[..genome.len()], genome.points[..]);
        let raw = amorph::voxel::voxelize(child, dims, 2, scene.threshold());
        for &(cell, to) in &site.sequence[..child.len() - genome.len()] {
            assert_eq!(raw.cells()[cell], to, "cell {cell}");
        }
    }
}

/// Every accepted insertion gives its voxel the state it aimed at in the voxelization, whatever
/// the design: the density comes from the field there, so this holds for any genome and cell.
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
        let p = child.points.last().expect("the new point");
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
