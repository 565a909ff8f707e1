//! Exports at the level of a run: every run writes a voxel-print slice stack of its best design
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
    let scene = &config.scene;
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

/// A run stopped by a signal between epochs (during a resume's replay, say) writes its results
/// at once and leaves the work that simulates its best design again for its real end: otherwise
/// a stopped arc run would spend 8–20 s on the twice-finer check after "stopping", and a 20³
/// robot would re-simulate its walk. Resumed to its end, the run writes it all.
#[test]
fn a_run_stopped_by_a_signal_leaves_the_end_of_run_work_for_its_end() {
    use amorph_coordinator::progress::Progress;
    use amorph_coordinator::store::RunStore;
    use amorph_coordinator::{LocalEvaluator, RunContext, StopReason};
    use std::sync::atomic::AtomicBool;

    let dir = scratch_dir("stopped-finish");
    let config = small_beam_config(&dir, 60, 4);
    let store = RunStore::create(&config, true).unwrap();
    let mut evaluator = LocalEvaluator::new(std::sync::Arc::new(config.scene.clone()), 2);
    let ctx = RunContext {
        store: &store,
        shutdown: &AtomicBool::new(true),
        progress: &Progress::hidden(),
    };
    let stopped = amorph_coordinator::run(&config, &mut evaluator, &ctx).unwrap();
    drop(store);
    assert_eq!(stopped.stop, StopReason::Shutdown);
    let run_dir = config.run_dir();
    let summary_json = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
    };
    let json = summary_json(&run_dir);
    assert_eq!(json["stop"], "shutdown");
    assert!(json.get("finer_check").is_none(), "{json}");
    assert!(!run_dir.join("exports/slices").exists());
    assert!(!run_dir.join("profile.png").exists());
    // What a stopped run still hands out: its best design and the files to make it.
    assert!(run_dir.join("best_genome.json").is_file());
    assert!(run_dir.join("exports/design.3mf").is_file());
    let report = std::fs::read_to_string(run_dir.join("report.md")).unwrap();
    assert!(report.contains("stopped before its end"), "{report}");

    let finished = amorph_tests::resume_locally(&config, 2);
    assert_ne!(finished.stop, StopReason::Shutdown);
    let json = summary_json(&run_dir);
    assert!(json["finer_check"]["finer_value"].is_number(), "{json}");
    assert!(run_dir.join("exports/slices/manifest.json").is_file());
    assert!(run_dir.join("profile.png").is_file());
    let report = std::fs::read_to_string(run_dir.join("report.md")).unwrap();
    assert!(!report.contains("stopped before its end"));
}
