//! Cluster benchmark, figures recorded in docs/how-to/cluster.md.
//!
//! - `capacity`: the coordinator alone, every evaluation trivial (workers in `Instant` mode answer
//!   at once): tasks dispatched and reported per second over loopback with 1, 2 and 8 worker
//!   processes, and the round-trip overhead of one evaluation with one single-slot worker.
//! - `scaling`: a beam run (configs/quickstart.toml's scene and search, fixed evaluation budget)
//!   with 1 and then 2 local workers of one thread each: evaluations per second and the ratio.
//!
//! Worker processes are this executable started again with AMORPH_BENCH_WORKER=URL, so the bench
//! needs nothing built besides itself.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use amorph::genome::Genome;
use amorph::voxel::GridDims;
use amorph_coordinator::RunConfig;
use amorph_coordinator::cluster::{self, ClusterEvaluator, QueueRules, ServerOptions, TaskQueue};
use amorph_coordinator::evaluator::{Evaluator, Task};
use amorph_coordinator::ids::TaskId;
use amorph_coordinator::job::{JobOptions, StoreMode, run_job};
use amorph_worker::{EvaluationMode, WorkerOptions, run_worker};

const WORKER_ENV: &str = "AMORPH_BENCH_WORKER";

fn main() {
    if let Ok(url) = std::env::var(WORKER_ENV) {
        let slots: usize = std::env::var("AMORPH_BENCH_SLOTS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1);
        worker_process(url, slots);
        return;
    }
    let mode = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .unwrap_or_else(|| "all".into());
    if mode == "capacity" || mode == "all" {
        capacity();
    }
    if mode == "scaling" || mode == "all" {
        scaling();
    }
}

fn worker_process(url: String, slots: usize) {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let mut opts = WorkerOptions::new(url, slots);
    opts.mode = EvaluationMode::Instant;
    opts.give_up_after = Some(Duration::from_secs(10));
    let (_stop, stop_rx) = tokio::sync::watch::channel(false);
    let _ = runtime.block_on(run_worker(opts, stop_rx));
}

fn spawn_workers(url: &str, count: usize, slots: usize) -> Vec<Child> {
    (0..count)
        .map(|_| {
            Command::new(std::env::current_exe().unwrap())
                .env(WORKER_ENV, url)
                .env("AMORPH_BENCH_SLOTS", slots.to_string())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect()
}

fn trivial_tasks(first: u64, n: usize) -> Vec<Task> {
    (0..n as u64)
        .map(|i| Task {
            id: TaskId(first + i),
            genome: Genome::default(),
            dims: GridDims::new(4, 12, 4),
        })
        .collect()
}

fn capacity() {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let scene = quickstart().scene;
    println!("capacity: trivial evaluations over loopback gRPC (batches of 20,000 tasks)");
    println!("| worker processes | slots each | tasks/s (best of 3) | µs per task |");
    println!("|---:|---:|---:|---:|");
    let mut next = 1u64;
    for (workers, slots) in [(1, 1), (1, 64), (2, 64), (8, 16)] {
        let queue = Arc::new(TaskQueue::new(QueueRules::default()));
        let server = runtime
            .block_on(cluster::start(
                &ServerOptions {
                    listen: "127.0.0.1:0".into(),
                    trust_everyone: true,
                    ..Default::default()
                },
                queue.clone(),
                &scene,
            ))
            .unwrap();
        let mut children = spawn_workers(&server.url(false), workers, slots);
        while queue.stats().workers < workers {
            std::thread::sleep(Duration::from_millis(10));
        }
        let mut evaluator = ClusterEvaluator::new(
            queue.clone(),
            Arc::new(AtomicBool::new(false)),
            Arc::new(scene.clone()),
        );
        let batch = if slots == 1 { 2_000 } else { 20_000 };
        // Warm-up batch, then the best of three.
        let mut best = f64::INFINITY;
        for round in 0..4 {
            let tasks = trivial_tasks(next, batch);
            next += batch as u64;
            let start = Instant::now();
            evaluator.evaluate(&tasks, &|_, _| {}).unwrap();
            if round > 0 {
                best = best.min(start.elapsed().as_secs_f64());
            }
        }
        let rate = batch as f64 / best;
        println!("| {workers} | {slots} | {rate:.0} | {:.1} |", 1e6 / rate);
        queue.finish();
        for child in &mut children {
            let _ = child.wait();
        }
        runtime.block_on(server.shutdown());
    }
}

fn quickstart() -> RunConfig {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/quickstart.toml");
    RunConfig::load(&path).unwrap()
}

fn scaling() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let results: PathBuf = manifest.join("../target/cluster-bench");
    println!("scaling: beam run, quickstart scene and search, 6x20x6 only, 600 evaluations");
    println!("| local workers | evaluations/s | speed-up |");
    println!("|---:|---:|---:|");
    let mut base = None;
    for workers in [1usize, 2] {
        let mut config = quickstart();
        config.name = format!("scaling-{workers}");
        config.results_dir = results.clone();
        config.budget.evaluations = Some(600);
        config.budget.wall_seconds = None;
        config.budget.target_rms_percent = None;
        config.resolution.levels.truncate(1);
        config.cluster.local_worker_threads = 1;
        let start = Instant::now();
        let summary = run_job(
            &config,
            JobOptions {
                store: StoreMode::Fresh,
                local_workers: Some(workers),
                ..JobOptions::default()
            },
        )
        .unwrap();
        let rate = summary.evaluations as f64 / start.elapsed().as_secs_f64();
        let speedup = rate / *base.get_or_insert(rate);
        println!("| {workers} | {rate:.1} | {speedup:.2}x |");
    }
}
