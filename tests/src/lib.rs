//! End-to-end test harness: run configurations built from the base files in `fixtures/configs/`
//! ([`test_config`]), each in its own temporary results folder, through the same code the
//! `coordinator` and `worker` binaries run: in one process (the reference), as an in-process
//! cluster on 127.0.0.1:0 with workers the test starts and kills, or as real processes.

pub mod http;
pub mod peer;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use amorph_coordinator::config::Override;
use amorph_coordinator::job::{JobError, JobOptions, StoreMode, run_job};
use amorph_coordinator::progress::Progress;
use amorph_coordinator::store::RunStore;
use amorph_coordinator::{LocalEvaluator, RunConfig, RunContext, RunSummary, run};
use amorph_worker::{ClientError, WorkerOptions, WorkerSummary, run_worker};

/// A fresh, empty folder for one test's results, unique to this call: the tests of one binary
/// run in parallel threads, and two of them asking for the same name must not delete each
/// other's run store mid-run.
pub fn scratch_dir(test: &str) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir()
        .join(format!("amorph-tests-{}", std::process::id()))
        .join(format!("{test}-{call}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// The repository's root folder, where the README, docs/ and configs/ are.
pub fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every file under `dir` (its subfolders too, but no hidden folder and no `target/`) whose
/// extension is one of `extensions`, sorted.
pub fn files_under(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let (mut files, mut folders) = (Vec::new(), vec![dir.to_owned()]);
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy();
            if path.is_dir() {
                if !name.starts_with('.') && name != "target" {
                    folders.push(path);
                }
            } else if path
                .extension()
                .is_some_and(|e| extensions.iter().any(|x| e == *x))
            {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The base run configs tests start from: `tests/fixtures/configs/<base>.toml`, each a complete
/// config (see the comment on its first line).
pub fn fixture_config(base: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/configs")
        .join(format!("{base}.toml"))
}

/// The base config `base` (a file in `tests/fixtures/configs/`) with `sets` applied as the
/// coordinator's `--set key=value` would (`"search.population=10"`, `"resolution.levels=[[4, 12,
/// 4]]"`, `"search.migration.topology={ kind = \"ring\" }"`), before its preset and validation,
/// writing to `results_dir`.
pub fn test_config(base: &str, results_dir: &Path, sets: &[&str]) -> RunConfig {
    let overrides: Vec<Override> = (sets.iter())
        .map(|s| s.parse().unwrap_or_else(|e| panic!("{base}: {e}")))
        .collect();
    let mut config = RunConfig::load_with(&fixture_config(base), &overrides)
        .unwrap_or_else(|e| panic!("{base}: {e}"));
    config.results_dir = results_dir.to_owned();
    config
}

/// A small beam run (`small_beam.toml`: 4x12x4, then 6x20x6 when it stalls, on the product's
/// default search) of `evaluations` from `seed`, written to `results_dir`. Cluster timings are
/// short so lost workers are noticed within a second.
pub fn small_beam_config(results_dir: &Path, evaluations: u64, seed: u64) -> RunConfig {
    test_config(
        "small_beam",
        results_dir,
        &[
            &format!("seed={seed}"),
            &format!("budget.evaluations={evaluations}"),
        ],
    )
}

/// The fingerprint of `small_beam_config(evaluations, seed)` run cleanly in this process: what
/// every attacked or faulty cluster run of it must end equal to.
pub fn clean_small_beam(evaluations: u64, seed: u64) -> String {
    let dir = scratch_dir(&format!("reference-{evaluations}-{seed}"));
    fingerprint(&run_locally(&small_beam_config(&dir, evaluations, seed), 2))
}

/// Runs a config in this process on `threads` evaluation threads: the reference every cluster
/// run must match bit for bit.
pub fn run_locally(config: &RunConfig, threads: usize) -> RunSummary {
    let store = RunStore::create(config, true).expect("run store");
    run_on(config, &store, threads)
}

/// Resumes the stopped run whose store `config` names, in this process, to its end.
pub fn resume_locally(config: &RunConfig, threads: usize) -> RunSummary {
    let store = RunStore::resume(config).expect("the stopped run's store");
    run_on(config, &store, threads)
}

/// Runs `make`'s config (given a fresh scratch folder) on 1 and on 3 evaluation threads, checks
/// that the two runs are bit-identical and returns the first with its config.
pub fn thread_count_blind(
    test: &str,
    make: impl Fn(&Path) -> RunConfig,
) -> (RunSummary, RunConfig) {
    let config = make(&scratch_dir(&format!("{test}-1")));
    let one = run_locally(&config, 1);
    let three = run_locally(&make(&scratch_dir(&format!("{test}-3"))), 3);
    assert_eq!(
        fingerprint(&one),
        fingerprint(&three),
        "{test}: 1 and 3 threads differ"
    );
    (one, config)
}

fn run_on(config: &RunConfig, store: &RunStore, threads: usize) -> RunSummary {
    let mut evaluator = LocalEvaluator::new(Arc::new(config.scene.clone()), threads);
    run(
        config,
        &mut evaluator,
        &RunContext {
            store,
            shutdown: &AtomicBool::new(false),
            progress: &Progress::hidden(),
        },
    )
    .expect("run completes")
}

/// Every island's final population (genomes and outcomes, with every bit of every number) as one
/// string: equal strings mean bit-identical runs.
pub fn fingerprint(summary: &RunSummary) -> String {
    let islands: Vec<Vec<(String, String)>> = summary
        .populations
        .iter()
        .map(|p| {
            p.iter()
                .map(|i| {
                    (
                        serde_json::to_string(&i.genome).expect("genome json"),
                        serde_json::to_string(&i.outcome).expect("outcome json"),
                    )
                })
                .collect()
        })
        .collect();
    serde_json::to_string(&islands).expect("fingerprint json")
}

/// A coordinator job running on its own thread, serving on 127.0.0.1:0.
#[derive(Debug)]
pub struct ClusterRun {
    pub addr: SocketAddr,
    pub store: PathBuf,
    job: JoinHandle<Result<RunSummary, JobError>>,
}

impl ClusterRun {
    /// Starts the job with `local_workers` in-process workers and waits until it listens.
    pub fn start(config: &RunConfig, local_workers: usize, token: Option<&str>) -> Self {
        let (tx, rx) = std::sync::mpsc::channel();
        let options = JobOptions {
            store: StoreMode::Fresh,
            listen: Some("127.0.0.1:0".into()),
            local_workers: Some(local_workers),
            token: token.map(str::to_owned),
            on_listening: Some(tx),
            ..JobOptions::default()
        };
        let cfg = config.clone();
        let job = std::thread::spawn(move || run_job(&cfg, options));
        let addr = rx
            .recv_timeout(Duration::from_secs(30))
            .expect("the coordinator listens within 30 s");
        Self {
            addr,
            store: RunStore::path_for(config),
            job,
        }
    }

    pub fn url(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// Waits for the run to end.
    pub fn join(self) -> RunSummary {
        self.job
            .join()
            .expect("coordinator thread")
            .expect("run completes")
    }

    /// Evaluations recorded in the run store so far.
    pub fn evaluations(&self) -> u64 {
        RunStore::peek_evaluation_count(&self.store).unwrap_or(0)
    }

    /// Blocks until the store holds at least `n` evaluations (panics after `timeout`).
    pub fn wait_for_evaluations(&self, n: u64, timeout: Duration) {
        let start = Instant::now();
        while self.evaluations() < n {
            assert!(
                start.elapsed() < timeout,
                "only {} of {n} evaluations after {timeout:?}",
                self.evaluations()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

/// A worker running on a runtime of its own, as a separate process would.
#[derive(Debug)]
pub struct TestWorker {
    runtime: tokio::runtime::Runtime,
    task: tokio::task::JoinHandle<Result<WorkerSummary, ClientError>>,
    stop: tokio::sync::watch::Sender<bool>,
}

impl TestWorker {
    pub fn start(url: &str, threads: usize, token: Option<&str>) -> Self {
        let mut opts = WorkerOptions::new(url, threads);
        opts.token = token.map(str::to_owned);
        opts.max_backoff = Duration::from_millis(200);
        opts.give_up_after = Some(Duration::from_secs(60));
        Self::with_options(opts)
    }

    pub fn with_options(opts: WorkerOptions) -> Self {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .expect("worker runtime");
        let (stop, stop_rx) = tokio::sync::watch::channel(false);
        let task = runtime.spawn(run_worker(opts, stop_rx));
        Self {
            runtime,
            task,
            stop,
        }
    }

    /// Kills the worker as a crash would: no goodbye, no hand-back, no reports of what it holds.
    pub fn kill(self) {
        self.task.abort();
        self.runtime.shutdown_background();
    }

    /// Asks the worker to stop as SIGTERM does (it stops leasing, finishes or hands back what it
    /// holds) and waits for it.
    pub fn stop(self) -> Result<WorkerSummary, ClientError> {
        let _ = self.stop.send(true);
        self.join()
    }

    /// Waits for the worker to end on its own (the run finished, or it was refused).
    pub fn join(self) -> Result<WorkerSummary, ClientError> {
        let _stop = self.stop;
        self.runtime
            .block_on(self.task)
            .expect("worker task did not panic")
    }
}

/// A workspace binary (`coordinator`, `worker`) next to this test's executable. `cargo test
/// --workspace` builds them; run it that way.
pub fn binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps/<test>");
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is missing: build the workspace binaries first (cargo test --workspace builds them)",
        path.display()
    );
    path
}
