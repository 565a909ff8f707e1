//! Local-search nudges from a plateaued design (issue 13), figures in docs/evolution.md.
//!
//! `cargo bench -p amorph-coordinator --bench nudge -- <design.json> <config.toml> <evaluations>
//! <points>,<probability>,<step>[,<insertion>[,flip_model]] [...]`: for each nudge setting (a last
//! `flip_model` draws the insertions by the task's flip model, `local_search.insertion_by`), a (1+1) climb from the design in
//! `design.json` (a `best_genome.json` or a test fixture: genome and resolution) under the scene
//! of `config.toml`, evaluating one nudge at a time and keeping it only if strictly fitter, as
//! crowding keeps a nudge of the best. Prints, per setting, the improvements, the nudges that left
//! the design unchanged, and the figure (RMS error for a beam) before and after. Seeded: the same
//! arguments give the same lines.
//!
//! The setting `voxels` climbs on the voxel design itself instead of the genome: each step gives
//! one voxel on the design's boundary (one whose state differs from a neighbour's) another state
//! (empty or a material), keeps what the task keeps, and evaluates. No genome can make a design
//! this climb cannot reach, so where it stalls says how far the resolution, not the search, limits
//! the figure.

#[path = "common/design.rs"]
mod design;

use amorph::genome::Genome;
use amorph::task::Outcome;
use amorph::task::{Scene, Task};
use amorph::voxel::VoxelGrid;
use amorph_coordinator::search::{InsertionBy, LocalSearchParams, other_state};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let args = design::arguments(
        4,
        "nudge <design.json> <config.toml> <evaluations> <points>,<probability>,<step>[,<insertion>]... | voxels",
    );
    let (genome, dims, config) = design::load(&args[0], &args[1]);
    let scene = &config.raw.scene;
    let evaluations: usize = args[2].parse().expect("evaluations");
    let figure = |o: &Outcome| scene.figure(o).unwrap_or(f64::NAN);
    let start = scene.evaluate(&genome, dims);
    for setting in &args[3..] {
        if setting == "voxels" {
            voxel_climb(
                scene,
                scene.design(&genome, dims),
                &start,
                evaluations,
                figure,
            );
            continue;
        }
        // A last word `flip_model` draws the insertions by the task's flip model.
        let (numbers, by) = match setting.strip_suffix(",flip_model") {
            Some(numbers) => (numbers, InsertionBy::FlipModel),
            None => (setting.as_str(), InsertionBy::Random),
        };
        let v: Vec<f64> = numbers
            .split(',')
            .map(|s| s.parse().expect("a number"))
            .collect();
        let local = LocalSearchParams {
            fraction: 1.0,
            points: v[0] as usize,
            probability: v[1],
            step: v[2],
            insertion: v.get(3).copied().unwrap_or(0.0),
            insertion_by: by,
            ..Default::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let (mut best, mut best_outcome) = (genome.clone(), start.clone());
        let mut best_design = scene.design(&best, dims);
        let site_of = |g: &Genome, o: &Outcome| local.boundary_site(g, o, scene, dims);
        let mut site = site_of(&best, &best_outcome);
        let (mut improved, mut unchanged) = (0, 0);
        for _ in 0..evaluations {
            let mut child = best.clone();
            local.step_from_best(&mut child, &mut rng, site.as_ref(), scene);
            let design = scene.design(&child, dims);
            if design == best_design {
                unchanged += 1;
                continue;
            }
            let outcome = scene.evaluate(&child, dims);
            if outcome.is_fitter_than(&best_outcome) {
                site = site_of(&child, &outcome);
                (best, best_outcome, best_design) = (child, outcome, design);
                improved += 1;
            }
        }
        println!(
            "points {} probability {} step {} insertion {} by {}: {evaluations} nudges, {improved} improved, {unchanged} left the design unchanged; figure {:.4} -> {:.4}",
            local.points,
            local.probability,
            local.step,
            local.insertion,
            local.insertion_by.key(),
            figure(&start),
            figure(&best_outcome)
        );
    }
}

fn voxel_climb(
    scene: &Scene,
    mut best: VoxelGrid,
    start: &Outcome,
    evaluations: usize,
    figure: impl Fn(&Outcome) -> f64,
) {
    let materials = scene.palette().len();
    let dims = best.dims();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut best_outcome = start.clone();
    let (mut improved, mut unchanged) = (0, 0);
    for _ in 0..evaluations {
        let boundary = best.boundary_cells();
        let i = boundary[rng.random_range(0..boundary.len())];
        let mut cells = best.cells().to_vec();
        cells[i] = other_state(cells[i], materials, &mut rng);
        let candidate = VoxelGrid::from_cells(dims, cells);
        let kept = match scene {
            Scene::Beam(beam) => beam.keep(&candidate),
            _ => panic!("the voxel climb is written for the beam task"),
        };
        if kept == best {
            unchanged += 1;
            continue;
        }
        let outcome = match scene {
            Scene::Beam(beam) => beam.simulate(&kept).map(amorph::task::Metrics::Beam),
            _ => unreachable!(),
        };
        if outcome.is_fitter_than(&best_outcome) {
            (best, best_outcome) = (kept, outcome);
            improved += 1;
        }
    }
    println!(
        "voxels: {evaluations} flips, {improved} improved, {unchanged} left the design unchanged; figure {:.4} -> {:.4}",
        figure(start),
        figure(&best_outcome)
    );
}
