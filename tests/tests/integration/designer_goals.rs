//! Goals a designer writes. Every config in `configs/` loads, is headed by what it runs and is in
//! the README's table (every base config the tests start from loads too); the stiffness task
//! evolves a design that beats the layouts beam theory ranks below the I-beam; a custom profile
//! runs end to end and is labelled as custom in the summary and report.

use std::path::Path;

use amorph::material::MaterialId;
use amorph::task::{Metrics, Scene, Task};
use amorph::voxel::{GridDims, VoxelGrid};
use amorph_coordinator::RunConfig;
use amorph_tests::{run_locally, scratch_dir, test_config};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[test]
fn every_config_in_configs_loads_says_what_it_runs_and_survives_its_own_effective_config() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let readme = std::fs::read_to_string(dir.join("../README.md")).unwrap();
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let config = RunConfig::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        // A user picks a config by its first lines and finds it in the README's table.
        let text = std::fs::read_to_string(&path).unwrap();
        let heading = text.lines().take_while(|l| l.starts_with('#')).count();
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(
            (1..=3).contains(&heading),
            "{name} starts with {heading} comment lines; one to three say what it runs"
        );
        assert!(
            readme.contains(&format!("`{name}`")),
            "{name} is not in the README's table"
        );
        // The effective config a run writes (and a resume reads back, from anywhere) is the same
        // run: files it named are inside it.
        let text = toml::to_string_pretty(&config.to_raw()).unwrap();
        let again = RunConfig::parse(&text, Path::new("/nonexistent/config.toml"))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(again.scene, config.scene, "{}", path.display());
        seen += 1;
    }
    assert_eq!(seen, 14, "the configs a user chooses from");
}

/// Every base config the tests start from (`tests/fixtures/configs/`, read by
/// `amorph_tests::test_config` and `deploy/fault-tests.sh`) loads as it stands, and its first line
/// says what it is for.
#[test]
fn every_test_fixture_config_loads_and_says_what_it_is_for() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/configs");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        RunConfig::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.lines().next().is_some_and(|l| l.starts_with("# ")),
            "{}: the first line says what the config is for",
            path.display()
        );
        seen += 1;
    }
    assert!(seen >= 7, "the fixtures the tests use: {seen}");
}

fn stiffness_config(results_dir: &Path) -> RunConfig {
    test_config("stiffness", results_dir, &[])
}

/// A full-workspace layout: hard where `hard` says, soft elsewhere.
fn layout(dims: GridDims, hard: impl Fn(usize, usize, usize) -> bool) -> VoxelGrid {
    let mut grid = VoxelGrid::empty(dims);
    for z in 0..dims.nz {
        for y in 0..dims.ny {
            for x in 0..dims.nx {
                let m = if hard(x, y, z) { 0 } else { 1 };
                grid.set(x, y, z, Some(MaterialId(m)));
            }
        }
    }
    grid
}

#[test]
fn an_evolved_stiff_design_beats_a_top_slab_and_a_random_layout_of_its_budget() {
    let config = stiffness_config(&scratch_dir("stiffness-run"));
    let summary = run_locally(&config, 2);
    let Scene::Stiffness(scene) = &config.scene else {
        panic!()
    };
    let best = summary.best();
    let Some(Metrics::Stiffness(evolved)) = best.outcome.metrics() else {
        panic!("no design evaluated: {:?}", best.outcome)
    };
    assert!(evolved.within_budget, "{evolved:?}");
    let dims = summary.dims;
    let stiffness = |grid: &VoxelGrid| match scene.simulate(grid) {
        amorph::task::TaskOutcome::Evaluated { metrics, .. } => metrics,
        failed => panic!("{failed:?}"),
    };
    // Hard material in the top 30 % of the 5 x 5 section: 7.5 cells a layer, so the top row of
    // five and two cells of the next (7, the most whole cells within the budget), soft below.
    let slab = stiffness(&layout(dims, |x, _, z| z == 4 || (z == 3 && x < 2)));
    assert!(slab.within_budget, "{slab:?}");
    // Exactly 30 % of the cells, drawn without replacement: a layout at the budget, never over.
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut picks = vec![false; dims.cell_count()];
    for i in rand::seq::index::sample(&mut rng, dims.cell_count(), dims.cell_count() * 3 / 10) {
        picks[i] = true;
    }
    let random = stiffness(&layout(dims, |x, y, z| picks[dims.index(x, y, z)]));
    eprintln!(
        "evolved {:.4} ({:.3} hard, flange efficiency {:.3}), top slab {:.4}, random {:.4} ({:.3} hard)",
        evolved.relative_stiffness,
        evolved.hard_fraction,
        evolved.flange_efficiency,
        slab.relative_stiffness,
        random.relative_stiffness,
        random.hard_fraction
    );
    assert!(random.within_budget, "{random:?}");
    assert!(evolved.relative_stiffness > slab.relative_stiffness);
    assert!(evolved.relative_stiffness > random.relative_stiffness);
    let md = std::fs::read_to_string(config.run_dir().join("summary.md")).unwrap();
    assert!(md.contains("hard fraction of the workspace"), "{md}");
}

#[test]
fn a_custom_profile_runs_and_is_reported_as_custom() {
    let dir = scratch_dir("custom-profile");
    let config = test_config("custom_points", &dir, &[]);
    run_locally(&config, 2);
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(config.run_dir().join("summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["target"], "custom (4 points)");
    assert!(json["paper_rms_percent"].is_null());
    let report = std::fs::read_to_string(config.run_dir().join("report.md")).unwrap();
    assert!(report.contains("custom (4 points)") && !report.contains("paper, simulated"));
    // The stored config keeps the points: the run resumes without the config's folder.
    let stored = std::fs::read_to_string(config.run_dir().join("config.toml")).unwrap();
    assert!(stored.contains("points"), "{stored}");
}
