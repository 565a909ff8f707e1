//! End-to-end test harness: run configurations built in code, each in its own temporary results
//! folder, through the same `run` the `coordinator` binary calls.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use amorph_coordinator::progress::Progress;
use amorph_coordinator::{LocalEvaluator, RunConfig, RunSummary, run};

/// A fresh, empty folder for one test's results, unique to this process.
pub fn scratch_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("amorph-tests-{}", std::process::id()))
        .join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A small beam run at 4x12x4 (then 6x20x6 when it stalls), written to `results_dir`.
pub fn small_beam_config(results_dir: &Path, evaluations: u64, seed: u64) -> RunConfig {
    let text = format!(
        r#"
name = "small"
seed = {seed}
results_dir = "{dir}"
[search]
population = 12
islands = 2
children_per_epoch = 8
initial_points = 20
[search.migration]
interval = 2
[budget]
evaluations = {evaluations}
[resolution]
levels = [[4, 12, 4], [6, 20, 6]]
stall_epochs = 3
[scene]
kind = "beam"
target = "circular_arc"
"#,
        dir = results_dir.display()
    );
    RunConfig::parse(&text, Path::new("small.toml")).expect("valid test config")
}

/// Runs a config on `threads` local evaluation threads.
pub fn run_locally(config: &RunConfig, threads: usize) -> RunSummary {
    let mut evaluator = LocalEvaluator::new(Arc::new(config.raw.scene.clone()), threads);
    run(
        config,
        &mut evaluator,
        &AtomicBool::new(false),
        &Progress::hidden(),
    )
    .expect("run completes")
}
