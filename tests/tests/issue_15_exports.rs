//! Issue 15 at the level of a run: every run writes a voxel-print slice stack of its best design
//! and checks that design at twice its final resolution, and the figures it reports are the ones
//! an independent evaluation gives. A bad `[export]` key is refused by name.

use std::path::Path;

use amorph::voxel::GridDims;
use amorph_coordinator::RunConfig;
use amorph_tests::{run_locally, scratch_dir, small_beam_config};

#[test]
fn a_run_writes_its_slice_stack_and_reports_its_design_at_twice_the_resolution() {
    let dir = scratch_dir("finer-check");
    let config = small_beam_config(&dir, 60, 4);
    let summary = run_locally(&config, 2);
    let run_dir = config.run_dir();
    let manifest: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(run_dir.join("exports/slices/manifest.json")).unwrap(),
    )
    .unwrap();
    let layers = manifest["layers"].as_u64().unwrap() as usize;
    // The beam is 40 mm long at any resolution, and its workspace is as high as it is wide.
    let voxel_mm = 40.0 / summary.dims.ny as f64;
    let height_mm = summary.dims.nz as f64 * voxel_mm;
    assert_eq!(layers, (height_mm / 0.027).ceil() as usize);
    let last = format!("exports/slices/slice-{layers:04}.png");
    assert!(run_dir.join(&last).is_file(), "{last}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run_dir.join("summary.json")).unwrap())
            .unwrap();
    let finer = &json["finer_check"];
    let dims = summary.dims;
    let twice = GridDims::new(2 * dims.nx, 2 * dims.ny, 2 * dims.nz);
    assert_eq!(finer["finer_resolution"], twice.to_string());
    // The reported figure is what evaluating the best genome at twice the resolution gives.
    let scene = &config.raw.scene;
    let best = summary.best();
    let independent = scene.figure(&scene.evaluate(&best.genome, twice)).unwrap();
    assert_eq!(finer["finer_value"].as_f64().unwrap(), independent);
    assert_eq!(
        finer["value"].as_f64().unwrap(),
        scene.figure(&best.outcome).unwrap()
    );
    let report = std::fs::read_to_string(run_dir.join("report.md")).unwrap();
    assert!(report.contains("Twice as fine"), "{report}");
    assert!(report.contains(&twice.to_string()));
    assert!(report.contains("slices/manifest.json"));
}

#[test]
fn export_keys_are_checked_by_name() {
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/quickstart.toml"),
    )
    .unwrap();
    for (section, expect) in [
        (
            "[export]\nprint_dpi = [0, 300]\n",
            "export.print_dpi[0] = 0",
        ),
        (
            "[export]\nprint_layer_mm = -1\n",
            "export.print_layer_mm = -1",
        ),
        ("[export]\nprint = 1\n", "invalid type"),
        ("[export]\nslices = true\n", "slices"),
    ] {
        let text = format!("{base}\n{section}");
        let error = RunConfig::parse(&text, Path::new("bad.toml"))
            .err()
            .unwrap_or_else(|| panic!("{section} was accepted"));
        assert!(error.to_string().contains(expect), "{section}: {error}");
    }
}
