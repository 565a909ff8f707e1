//! The beam's flip model against the static solver (issue 13, `local_search.insertion_by =
//! "flip_model"`): the layered cantilever must say which single-voxel changes of an evolved
//! design help, far more often than chance, or guiding the climb's insertions by it means nothing.

use amorph::genome::Genome;
use amorph::material::MaterialId;
use amorph::task::beam::{BeamFlipModel, BeamMetrics, BeamScene};
use amorph::task::{FlipModel, Task, TaskOutcome, design};
use amorph::voxel::{GridDims, VoxelGrid};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The circular arc's best design when one of session 34's runs reached 12x40x12 (0.919 %).
fn evolved_arc() -> (BeamScene, Genome, GridDims) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/data/climb/arc_8x6_s15_first_fine_epoch.json"
    );
    let design: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("the design file"))
            .expect("design JSON");
    let genome: Genome = serde_json::from_value(design["genome"].clone()).expect("a genome");
    let r: Vec<usize> = serde_json::from_value(design["resolution"].clone()).expect("resolution");
    let scene = toml::from_str("target = \"circular_arc\"").expect("a beam");
    (scene, genome, GridDims::new(r[0], r[1], r[2]))
}

fn solve(scene: &BeamScene, grid: &VoxelGrid) -> Option<BeamMetrics> {
    match scene.simulate(&scene.keep(grid)) {
        TaskOutcome::Evaluated { metrics, .. } => Some(metrics),
        _ => None,
    }
}

fn squares(m: &BeamMetrics) -> f64 {
    m.profile[1..].iter().map(|[_, w, t]| (w - t).powi(2)).sum()
}

#[test]
fn the_flip_model_tells_helping_flips_from_hurting_ones() {
    let (scene, genome, dims) = evolved_arc();
    let design = design(&scene, &genome, dims);
    let metrics = solve(&scene, &design).expect("the design evaluates");
    let before = squares(&metrics);
    let model = BeamFlipModel::new(&scene, &design, &metrics).expect("a model of the design");
    let boundary = design.boundary_cells();
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let (mut agree, mut judged) = (0, 0);
    let mut pairs = Vec::new();
    for _ in 0..60 {
        let cell = boundary[rng.random_range(0..boundary.len())];
        let states = [None, Some(MaterialId(0)), Some(MaterialId(1))];
        let others: Vec<_> = states
            .into_iter()
            .filter(|&s| s != design.cells()[cell])
            .collect();
        let to = others[rng.random_range(0..others.len())];
        let predicted = model.gain(cell, to);
        let mut flipped = design.clone();
        let [x, y, z] = dims.coords(cell);
        flipped.set(x, y, z, to);
        let Some(after) = solve(&scene, &flipped) else {
            continue;
        };
        let measured = before - squares(&after);
        pairs.push((predicted, measured));
        // A change the solver cannot tell from nothing says nothing about the model's sign.
        if predicted.is_finite() && measured.abs() > 1e-4 * before {
            judged += 1;
            agree += usize::from((predicted > 0.0) == (measured > 0.0));
        }
    }
    eprintln!("{agree} of {judged} signs agree; pairs {pairs:?}");
    // Under a model no better than a coin the agreement is binomial(judged, 1/2): demand three
    // standard deviations above its mean.
    let chance = judged as f64 / 2.0 + 3.0 * (judged as f64 / 4.0).sqrt();
    assert!(judged >= 30, "only {judged} flips changed the profile");
    assert!(agree as f64 >= chance, "{agree} of {judged} signs agree");
}
