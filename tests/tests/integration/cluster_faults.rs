//! The cluster with the real binaries as processes: a coordinator killed mid-run and resumed from its
//! run store, and `worker --connect` processes killed or stopped mid-run, all end bit-identical to
//! the same run done in one process.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use amorph_coordinator::store::RunStore;
use amorph_tests::{ClusterRun, binary, fingerprint, run_locally, scratch_dir, small_beam_config};

const EVALUATIONS: u64 = 300;
const SEED: u64 = 11;

/// The small test config as a file, with `local_workers` in-process workers.
fn config_file(dir: &Path, local_workers: usize) -> PathBuf {
    let mut raw = small_beam_config(dir, EVALUATIONS, SEED).to_raw();
    raw.cluster.local_workers = Some(local_workers);
    let path = dir.join("run.toml");
    std::fs::write(&path, toml_text(&raw)).unwrap();
    path
}

fn toml_text(raw: &amorph_coordinator::config::RawConfig) -> String {
    // The config types serialize to the TOML they parse from.
    toml::to_string(raw).unwrap()
}

fn wait_for_store(path: &Path, n: u64, child: &mut Child) {
    let start = Instant::now();
    loop {
        let count = RunStore::peek_evaluation_count(path).unwrap_or(0);
        if count >= n {
            return;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "the process ended early"
        );
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "{count} of {n} evaluations"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs the coordinator on `config` and SIGKILLs it once half the evaluations are in `store`
/// (no chance to tidy up); returns when it was killed (Unix seconds) and what the store held.
fn kill_half_way(config: &Path, store: &Path) -> (f64, u64) {
    let mut first = Command::new(binary("coordinator"))
        .args(["--config", config.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for_store(store, EVALUATIONS / 2, &mut first);
    first.kill().unwrap();
    first.wait().unwrap();
    let killed_at = now_unix();
    let stored = RunStore::peek_evaluation_count(store).unwrap();
    assert!(stored < EVALUATIONS, "killed mid-run ({stored} stored)");
    (killed_at, stored)
}

/// `coordinator --resume` on `config` finishes the run with the uninterrupted run's population.
fn resume_to_the_end(config: &Path, population: &Path, expected: &[u8]) {
    let out = Command::new(binary("coordinator"))
        .args(["--config", config.to_str().unwrap(), "--resume"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        String::from_utf8_lossy(&out.stdout).contains(&format!("after {EVALUATIONS} evaluations")),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let resumed = std::fs::read(population).unwrap();
    assert!(
        resumed == expected,
        "resumed run differs from the uninterrupted one"
    );
}

/// The uninterrupted run's `population.json`, run once for every test that compares with it.
fn uninterrupted_population() -> &'static [u8] {
    static POPULATION: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    POPULATION.get_or_init(|| {
        let reference_dir = scratch_dir("resume-reference");
        run_locally(&small_beam_config(&reference_dir, EVALUATIONS, SEED), 2);
        std::fs::read(reference_dir.join("small/population.json")).unwrap()
    })
}

#[test]
fn a_killed_coordinator_resumes_from_its_store_and_ends_bit_identical() {
    let expected = uninterrupted_population();
    let dir = scratch_dir("resume");
    let config = config_file(&dir, 2);
    let store = dir.join("small/run.sqlite");
    let (killed_at, stored) = kill_half_way(&config, &store);
    resume_to_the_end(&config, &dir.join("small/population.json"), expected);

    // Every task is stored once, and nothing finished before the kill was evaluated again.
    let conn = rusqlite_count(&store, "SELECT COUNT(*) FROM evaluation");
    assert_eq!(conn, EVALUATIONS);
    let before = rusqlite_count(
        &store,
        &format!("SELECT COUNT(*) FROM evaluation WHERE finished_unix <= {killed_at}"),
    );
    assert_eq!(
        before, stored,
        "evaluations from before the kill were kept, not redone"
    );
}

/// A killed run's folder moved elsewhere (a study cut short on a lent machine and finished on
/// another) resumes there under a config that names the new `results_dir`, and ends as the
/// uninterrupted run.
#[test]
fn a_killed_run_moved_to_another_results_dir_resumes_bit_identical() {
    let expected = uninterrupted_population();
    let from = scratch_dir("moved-from");
    kill_half_way(&config_file(&from, 2), &from.join("small/run.sqlite"));
    let to = scratch_dir("moved-to");
    std::fs::rename(from.join("small"), to.join("small")).unwrap();
    let config = config_file(&to, 2);
    resume_to_the_end(&config, &to.join("small/population.json"), expected);
    assert!(
        !from.join("small").exists(),
        "nothing was written to the old place"
    );
}

#[test]
fn worker_processes_killed_or_stopped_mid_run_change_nothing() {
    let reference_dir = scratch_dir("processes-reference");
    let expected = fingerprint(&run_locally(
        &small_beam_config(&reference_dir, EVALUATIONS, SEED),
        2,
    ));
    let config = small_beam_config(&scratch_dir("processes"), EVALUATIONS, SEED);
    let run = ClusterRun::start(&config, 0, None);
    let worker = |name: &str| {
        Command::new(binary("worker"))
            .args(["--connect", &run.url(), "--threads", "1", "--name", name])
            .args(["--grace-seconds", "0", "--give-up-after", "60"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut steady = worker("steady");
    let mut killed = worker("killed");
    let stopped = worker("stopped");
    run.wait_for_evaluations(EVALUATIONS / 4, Duration::from_secs(120));
    killed.kill().unwrap();
    killed.wait().unwrap();
    // SIGTERM: stop leasing, hand back what is running (grace 0), exit cleanly.
    let status = Command::new("kill")
        .args(["-TERM", &stopped.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = stopped.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("handed back"), "{stderr}");

    let summary = run.join();
    assert_eq!(fingerprint(&summary), expected);
    assert!(steady.wait().unwrap().success());
}

fn now_unix() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

fn rusqlite_count(path: &Path, sql: &str) -> u64 {
    let conn =
        rusqlite::Connection::open_with_flags(path, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .unwrap();
    conn.query_row(sql, [], |r| r.get::<_, i64>(0)).unwrap() as u64
}
