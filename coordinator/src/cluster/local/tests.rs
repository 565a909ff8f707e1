use super::*;
use crate::cluster::QueueRules;
use crate::evaluator::Origin;
use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::voxel::GridDims;
use std::time::Duration;

fn beam() -> Arc<Scene> {
    Arc::new(toml::from_str("kind = \"beam\"\ntarget = \"straight\"").unwrap())
}

/// A bar of hard material from the clamped wall to the tip: a beam the solver really loads
/// and measures.
fn block(density: f64) -> Genome {
    let point = |y: f64| GaussianPoint {
        position: [0.5, y, 0.5],
        density,
        falloff: 0.3,
        material: MaterialId(1),
    };
    Genome::new((0..=4).map(|i| point(f64::from(i) / 4.0)).collect())
}

fn tasks(n: u64) -> Vec<Task> {
    (1..=n)
        .map(|i| Task {
            id: TaskId(i),
            genome: block(0.3 + i as f64 / 10.0),
            dims: GridDims::new(4, 12, 4),
        })
        .collect()
}

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

#[test]
fn local_workers_evaluate_every_task_once_exactly_as_the_scene_does() {
    let rt = runtime();
    let queue = Arc::new(TaskQueue::new(QueueRules::default()));
    let scene = beam();
    let batch = tasks(6);
    let rx = queue.submit(batch.clone());
    let (stop, stop_rx) = watch::channel(false);
    let workers: Vec<_> = (0..2)
        .map(|i| {
            let w = LocalWorker::new(queue.clone(), scene.clone(), format!("l{i}"), 2, 1 << 40);
            rt.spawn(w.run(stop_rx.clone()))
        })
        .collect();
    let mut done: Vec<_> = (0..batch.len())
        .map(|_| {
            rx.recv_timeout(Duration::from_secs(60))
                .expect("a completion")
        })
        .collect();
    done.sort_by_key(|c| c.slot);
    for (c, task) in done.iter().zip(&batch) {
        assert!(
            c.outcome.fitness().is_some(),
            "a real evaluation: {:?}",
            c.outcome
        );
        assert_eq!(
            c.outcome,
            scene.evaluate(&task.genome, task.dims),
            "slot {}",
            c.slot
        );
        assert_eq!(c.origin, Origin::Trusted, "computed in this process");
    }
    assert!(rx.try_recv().is_err(), "each task completes once");
    queue.finish();
    let evaluated: u64 = workers
        .into_iter()
        .map(|w| rt.block_on(w).unwrap().unwrap().evaluated)
        .sum();
    assert_eq!(evaluated, 6);
    drop(stop);
}

#[test]
fn a_stopped_local_worker_hands_its_leases_back() {
    let rt = runtime();
    let queue = Arc::new(TaskQueue::new(QueueRules::default()));
    // The finest grid the beam takes keeps the evaluation running (about a second) while
    // the stop arrives, a millisecond after the lease.
    let slow = Task {
        id: TaskId(1),
        genome: block(1.0),
        dims: GridDims::new(24, 80, 24),
    };
    let _rx = queue.submit(vec![slow]);
    let (stop, stop_rx) = watch::channel(false);
    let worker = LocalWorker::new(queue.clone(), beam(), "l".into(), 1, 1 << 40);
    let handle = rt.spawn(worker.run(stop_rx));
    let deadline = Instant::now() + Duration::from_secs(60);
    while queue.stats().leased == 0 {
        assert!(
            Instant::now() < deadline,
            "the worker never leased the task"
        );
        std::thread::sleep(Duration::from_millis(1));
    }
    stop.send_replace(true);
    let summary = rt.block_on(handle).unwrap().unwrap();
    assert_eq!(summary.released, 1);
    assert_eq!(
        queue.stats().queued,
        1,
        "back in the queue for another worker"
    );
}

#[test]
fn a_local_worker_stopped_at_the_finish_leaves_nobody_to_wait_for() {
    // The job finishes the queue and stops its local workers together; a worker that sees
    // the stop first never hears of the finish, and the end of the run waited a
    // worker_timeout and more for the reaper to drop it (4.6 s on a 480-evaluation run,
    // with a "went silent" warning per worker).
    let rt = runtime();
    let queue = Arc::new(TaskQueue::new(QueueRules::default()));
    let (stop, stop_rx) = watch::channel(false);
    let worker = LocalWorker::new(queue.clone(), beam(), "l".into(), 1, 1 << 40);
    let handle = rt.spawn(worker.run(stop_rx));
    let deadline = Instant::now() + Duration::from_secs(60);
    while queue.stats().workers == 0 {
        assert!(Instant::now() < deadline, "the worker never registered");
        std::thread::sleep(Duration::from_millis(1));
    }
    stop.send_replace(true);
    queue.finish();
    rt.block_on(handle).unwrap().unwrap();
    assert!(queue.everyone_told(), "the stopped worker still counts");
}

#[test]
fn a_task_over_the_memory_budget_is_refused_before_it_starts() {
    let rt = runtime();
    let queue = Arc::new(TaskQueue::new(QueueRules::default()));
    let _rx = queue.submit(tasks(1));
    let (_stop, stop_rx) = watch::channel(false);
    // Below the 16 MiB every evaluation needs whatever its size.
    let worker = LocalWorker::new(queue.clone(), beam(), "small".into(), 1, 1 << 20);
    let handle = rt.spawn(worker.run(stop_rx));
    let noted = loop {
        let noted = queue.take_noted_errors();
        if !noted.is_empty() {
            break noted;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    assert!(noted[0].2.contains("budget"), "{noted:?}");
    queue.finish();
    assert_eq!(rt.block_on(handle).unwrap().unwrap().evaluated, 0);
}
