//! The `coordinator` binary as a user runs it: bad input gives one clear line and a failure code.

use std::process::Command;

fn coordinator(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_coordinator"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("coordinator runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn write_config(name: &str, text: &str) -> std::path::PathBuf {
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The smallest straight-beam run, the base config the workspace's tests share.
const GOOD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../tests/fixtures/configs/cli_straight.toml"
);

fn good_text() -> String {
    std::fs::read_to_string(GOOD).expect("the cli_straight fixture")
}

/// `--set results_dir=<dir>`, as TOML.
fn results_dir(dir: &std::path::Path) -> String {
    format!("results_dir={:?}", dir.display().to_string())
}

#[test]
fn a_misspelt_key_is_one_line_naming_it() {
    let text = good_text().replace("evaluations", "evalutions");
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("evalutions"))
        .unwrap();
    let path = write_config("misspelt.toml", &text);
    let (ok, stderr) = coordinator(&["--config", path.to_str().unwrap()]);
    assert!(!ok);
    let errors: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("evalutions") && errors[0].contains(&format!("line {line}:")),
        "{stderr}"
    );
}

#[test]
fn a_missing_config_file_is_named() {
    let (ok, stderr) = coordinator(&["--config", "/nonexistent/run.toml"]);
    assert!(!ok);
    assert!(stderr.contains("/nonexistent/run.toml"), "{stderr}");
}

#[test]
fn a_small_run_completes_and_reports_its_results_folder() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-results");
    let set_dir = results_dir(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_coordinator"))
        .args(["--config", GOOD, "--set", &set_dir])
        .args(["--local-workers", "2", "--fresh"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("after 10 evaluations"), "{stdout}");
    assert!(dir.join("cli").join("summary.md").is_file());
    assert!(dir.join("cli").join("run.sqlite").is_file());

    // Running it again would overwrite a finished run: refused, naming the store and the ways on.
    let (ok, stderr) = coordinator(&["--config", GOOD, "--set", &set_dir]);
    assert!(!ok);
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].contains("run.sqlite")
            && errors[0].contains("--resume")
            && errors[0].contains("--fresh"),
        "{stderr}"
    );
}

#[test]
fn a_beam_resolution_lying_on_its_side_is_refused_with_the_fix() {
    let path = write_config(
        "sideways.toml",
        &good_text().replace("levels = [[4, 12, 4]]", "levels = [[4, 4, 12]]"),
    );
    let (ok, stderr) = coordinator(&["--config", path.to_str().unwrap()]);
    assert!(!ok);
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("resolution.levels[0]") && stderr.contains("[4, 12, 4]"),
        "{stderr}"
    );
}

/// `--set` changes a key as the file would, is recorded in the run's config.toml, and a bad one
/// is refused in one line that names it.
#[test]
fn set_overrides_a_key_and_is_recorded() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-set");
    let path = GOOD;
    let out = Command::new(env!("CARGO_BIN_EXE_coordinator"))
        .args(["--config", path, "--fresh", "--local-workers", "1"])
        .args(["--set", &results_dir(&dir)])
        .args([
            "--set",
            "budget.evaluations=12",
            "--set",
            "scene.target=polynomial4",
        ])
        .args(["--set", "search.preset=paper"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("after 12 evaluations"), "{stdout}");
    let recorded = std::fs::read_to_string(dir.join("cli").join("config.toml")).unwrap();
    let recorded: toml::Table = recorded.parse().unwrap();
    assert_eq!(recorded["scene"]["target"].as_str(), Some("polynomial4"));
    assert_eq!(recorded["search"]["preset"].as_str(), Some("paper"));
    assert_eq!(recorded["budget"]["evaluations"].as_integer(), Some(12));

    for (bad, named) in [
        (
            "search.local_search.fraction=3",
            "search.local_search.fraction",
        ),
        ("budget.evalutions=5", "evalutions"),
        ("fraction", "expected key=value"),
    ] {
        let (ok, stderr) = coordinator(&["--config", path, "--set", bad]);
        assert!(!ok, "{bad}");
        let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(errors.len(), 1, "{bad}: {stderr}");
        assert!(errors[0].contains(named), "{bad}: {stderr}");
    }
}
