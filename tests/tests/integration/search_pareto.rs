//! Runs with several objectives (`[search] objectives`): under either selection the run is
//! deterministic, its `pareto.csv` is exactly the non-dominated set of every design it evaluated
//! at its final resolution, valued as the task values them, and `history.csv` carries each
//! island's hypervolume. A bad objective key is refused by name.

use std::path::Path;

use amorph::task::Outcome;
use amorph::voxel::GridDims;
use amorph_coordinator::RunConfig;
use amorph_coordinator::search::dominates;
use amorph_tests::{binary, fixture_config, scratch_dir, test_config, thread_count_blind};

const REFERENCE: [f64; 2] = [100.0, 1.0];

fn config(dir: &Path, selection: &str) -> RunConfig {
    test_config(
        "small_beam",
        dir,
        &[
            "search.objectives=[\"rms\", \"hard_fraction\"]",
            "search.hypervolume_reference=[100.0, 1.0]",
            &format!("search.selection=\"{selection}\""),
            "budget.evaluations=240",
        ],
    )
}

/// Every design the run stored at `dims`, with its objective values, read back from the store.
fn stored_values(config: &RunConfig, dims: GridDims) -> Vec<(u64, Vec<f64>)> {
    let store = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let mut rows = store
        .prepare("SELECT task_id, outcome FROM evaluation WHERE resolution = ?1")
        .unwrap();
    let rows: Vec<(i64, String)> = rows
        .query_map([dims.to_string()], |r| Ok((r.get(0)?, r.get(1)?)))
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    rows.into_iter()
        .filter_map(|(task, outcome)| {
            let outcome: Outcome = serde_json::from_str(&outcome).unwrap();
            let all = config.scene.objective_values(&outcome, dims)?;
            // rms is the beam's first objective, hard_fraction its second.
            Some((task as u64, vec![all[0], all[1]]))
        })
        .collect()
}

fn front_rows(config: &RunConfig) -> Vec<(u64, Vec<f64>)> {
    let text = std::fs::read_to_string(config.run_dir().join("pareto.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("task_id,rms,hard_fraction"));
    lines
        .map(|line| {
            let mut fields = line.split(',');
            let task = fields.next().unwrap().parse().unwrap();
            (task, fields.map(|f| f.parse().unwrap()).collect())
        })
        .collect()
}

fn pareto_run(selection: &str) {
    let (summary, config) =
        thread_count_blind(&format!("pareto-{selection}"), |dir| config(dir, selection));
    assert_eq!(summary.evaluations, 240);
    let stored = stored_values(&config, summary.dims);
    let front = front_rows(&config);
    assert!(!front.is_empty());
    for (task, values) in &front {
        // Each row is the stored design's own values, to the bit...
        let own = stored
            .iter()
            .find(|(t, _)| t == task)
            .expect("a stored design");
        assert_eq!(&own.1, values, "task {task}");
        // ...and no design the run evaluated at this resolution dominates it.
        assert!(stored.iter().all(|(_, other)| !dominates(other, values)));
    }
    // Every other design is dominated by a row, or repeats one.
    for (task, values) in &stored {
        assert!(
            (front.iter()).any(|(t, row)| t == task || row == values || dominates(row, values)),
            "task {task} {values:?} is neither on the front nor behind it"
        );
    }
    // history.csv: a hypervolume per island and epoch, inside the reference box's.
    let history = std::fs::read_to_string(config.run_dir().join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert!(lines.next().unwrap().ends_with(",replacements,hypervolume"));
    for line in lines {
        let hv: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
        assert!((0.0..=REFERENCE[0] * REFERENCE[1]).contains(&hv), "{line}");
    }
}

#[test]
fn a_pareto_crowding_run_writes_its_front_and_hypervolume() {
    pareto_run("crowding");
}

/// Any front member comes back from the run folder by its id: `worker evaluate --run DIR
/// --design ID` evaluates the stored genome at its stored resolution to the row's values.
#[test]
fn a_front_member_is_exported_by_its_id() {
    let dir = scratch_dir("pareto-export");
    let config = config(&dir, "crowding");
    let summary = amorph_tests::run_locally(&config, 2);
    let (task, values) = front_rows(&config).pop().expect("a front");
    let run = config.run_dir();
    // `worker <command> --run <run> --design <id> <more>`, with its output.
    let worker = |command: &str, id: &str, more: &[&Path]| {
        std::process::Command::new(binary("worker"))
            .args([command, "--run"])
            .arg(&run)
            .args(["--design", id])
            .args(more.iter().flat_map(|p| [Path::new("--out"), p]))
            .output()
            .unwrap()
    };
    let succeeded = |out: &std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let out = worker("evaluate", &task.to_string(), &[]);
    succeeded(&out);
    let outcome: Outcome = serde_json::from_slice(&out.stdout).unwrap();
    let all = config
        .scene
        .objective_values(&outcome, summary.dims)
        .unwrap();
    assert_eq!(vec![all[0], all[1]], values);
    let exported = dir.join("exported");
    succeeded(&worker("export", &task.to_string(), &[&exported]));
    assert!(exported.join("design.3mf").is_file());
    let missing = worker("evaluate", "999999", &[]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no evaluation has task_id 999999"));
}

#[test]
fn an_nsga2_run_writes_its_front_and_hypervolume() {
    pareto_run("nsga2");
}

#[test]
fn objective_keys_are_checked_by_name() {
    let base = fixture_config("small_beam");
    for (sets, expect) in [
        (
            &["search.objectives=[\"rms\", \"speed\"]"][..],
            "search.objectives[1] = \"speed\" is not an objective of a beam scene; it has rms, hard_fraction, voxels, mass",
        ),
        (&["search.objectives=[\"rms\"]"], "two or more objectives"),
        (
            &["search.objectives=[\"rms\", \"rms\"]"],
            "search.objectives[1] = \"rms\" is named twice",
        ),
        (
            &["search.objectives=[\"rms\", \"voxels\"]"],
            "search.hypervolume_reference must hold one finite number per objective (2)",
        ),
        (
            &["search.selection=\"crowding\""],
            "search.selection needs search.objectives",
        ),
        (
            &[
                "search.objectives=[\"rms\", \"voxels\"]",
                "search.hypervolume_reference=[1.0, 10.0]",
                "search.local_search.fraction=0.5",
            ],
            "search.local_search.fraction must be 0 with search.objectives",
        ),
    ] {
        let overrides: Vec<_> = sets.iter().map(|s| s.parse().unwrap()).collect();
        let err = RunConfig::load_with(&base, &overrides)
            .unwrap_err()
            .to_string();
        assert!(err.contains(expect), "{sets:?}: {err}");
    }
    // With objectives and no preset named, a beam runs the paper's search, not the climb.
    let dir = scratch_dir("pareto-preset");
    let config = config(&dir, "crowding");
    assert_eq!(config.search.local_search.fraction, 0.0);
    assert_eq!(config.search.preset.key(), "paper");
}
