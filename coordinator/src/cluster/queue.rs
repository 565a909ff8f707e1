//! The task queue with leases: the coordinator's whole bookkeeping of who evaluates what.
//!
//! A synchronous state machine behind one mutex, with the time passed in, so every rule (lease
//! expiry, silent workers, duplicate and late reports, retries) is unit-tested without a network.
//! The gRPC service calls it; the search submits one batch at a time and collects its completions
//! from a channel as they arrive (so the run store records each one at once).
//!
//! Rules:
//! - A lease lasts `lease` from when it is granted or last named in a heartbeat. A lease past its
//!   deadline, or held by a worker silent for `worker_timeout`, goes back to the front of the queue.
//! - The first outcome reported for a task wins, even from a worker whose lease has lapsed (the
//!   evaluation is a pure function, so a late outcome is as good as any); later ones are duplicates.
//! - A worker may report only tasks it was leased at some point; anything else is refused.
//! - A worker's error for a task (or a malformed outcome) is noted and the task goes back to the
//!   queue; after `max_attempts` such errors it is marked failed with their reasons.

use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use amorph::outcome::Failure;
use amorph::task::Outcome;
use tracing::{info, warn};

use crate::evaluator::{Completion, Task};

/// Timing and retry rules of the queue.
#[derive(Clone, Debug, PartialEq)]
pub struct QueueRules {
    /// How long a lease lasts without a heartbeat naming its task.
    pub lease: Duration,
    /// How often workers are asked to heartbeat.
    pub heartbeat_interval: Duration,
    /// A worker silent this long is dropped and its leases go back to the queue.
    pub worker_timeout: Duration,
    /// Worker errors after which a task is marked failed rather than retried.
    pub max_attempts: u32,
}

impl Default for QueueRules {
    fn default() -> Self {
        Self {
            lease: Duration::from_secs(30),
            heartbeat_interval: Duration::from_secs(1),
            worker_timeout: Duration::from_secs(5),
            max_attempts: 3,
        }
    }
}

/// What a report did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Disposition {
    Accepted,
    Duplicate,
    ErrorNoted,
}

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum QueueError {
    #[error("worker {0} is not registered (register again)")]
    UnknownWorker(String),
    #[error("task {0} does not exist")]
    UnknownTask(u64),
    #[error("task {task} was never leased to worker {worker}")]
    NotLeasedTo { task: u64, worker: String },
}

/// Counts for progress lines and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QueueStats {
    pub workers: usize,
    pub queued: usize,
    pub leased: usize,
    pub dispatched: u64,
    pub completed: u64,
    pub duplicates: u64,
    pub worker_errors: u64,
    pub expired_leases: u64,
}

#[derive(Debug)]
struct WorkerState {
    name: String,
    capacity: u32,
    last_seen: Instant,
    leased: HashSet<u64>,
}

#[derive(Debug)]
enum TaskPhase {
    Queued,
    Leased { worker: String, deadline: Instant },
    Done,
}

#[derive(Debug)]
struct TaskState {
    task: Arc<Task>,
    slot: usize,
    phase: TaskPhase,
    /// Every worker the task was ever leased to: only they may report it.
    leased_to: Vec<String>,
    errors: Vec<String>,
}

#[derive(Debug)]
struct State {
    workers: HashMap<String, WorkerState>,
    /// Ids this coordinator process gave out, live or dropped: a dropped worker's late report is
    /// still welcome.
    issued_workers: HashSet<String>,
    next_worker: u64,
    tasks: HashMap<u64, TaskState>,
    queue: VecDeque<u64>,
    /// Highest task id ever submitted: ids at or below it that are no longer in `tasks` belonged to
    /// finished batches (so a report for one is a duplicate, not an unknown task).
    highest_task: u64,
    completions: Option<Sender<Completion>>,
    /// Worker errors not yet handed to the run store: (task, worker, message).
    noted_errors: Vec<(u64, String, String)>,
    run_finished: bool,
    stats: QueueStats,
}

/// The queue shared by the gRPC service, the reaper and the search.
#[derive(Debug)]
pub struct TaskQueue {
    rules: QueueRules,
    /// Distinguishes this coordinator process's worker ids from a previous one's (after a resume).
    epoch_tag: String,
    state: Mutex<State>,
    /// Wakes leases waiting for work (and for the end of the run).
    work: tokio::sync::Notify,
}

impl TaskQueue {
    pub fn new(rules: QueueRules) -> Self {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        Self {
            rules,
            epoch_tag: format!(
                "{:06x}",
                (nanos ^ (u128::from(std::process::id()) << 20)) & 0xff_ffff
            ),
            state: Mutex::new(State {
                workers: HashMap::new(),
                issued_workers: HashSet::new(),
                next_worker: 0,
                tasks: HashMap::new(),
                queue: VecDeque::new(),
                highest_task: 0,
                completions: None,
                noted_errors: Vec::new(),
                run_finished: false,
                stats: QueueStats::default(),
            }),
            work: tokio::sync::Notify::new(),
        }
    }

    pub fn rules(&self) -> &QueueRules {
        &self.rules
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock would be a bug in this file; the state is still
        // consistent between statements, so carry on rather than poison every later call.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Waits until work may be available (a batch was submitted, a lease came back, the run
    /// ended). Create the future *before* checking the queue so no wake-up is missed.
    pub fn work_notified(&self) -> tokio::sync::futures::Notified<'_> {
        self.work.notified()
    }

    pub fn register(&self, name: &str, capacity: u32, now: Instant) -> String {
        let mut s = self.lock();
        s.next_worker += 1;
        let id = format!("w{}-{}", s.next_worker, self.epoch_tag);
        s.workers.insert(
            id.clone(),
            WorkerState {
                name: name.to_owned(),
                capacity,
                last_seen: now,
                leased: HashSet::new(),
            },
        );
        s.issued_workers.insert(id.clone());
        info!(worker = %id, name, capacity, "worker registered");
        id
    }

    /// Up to `max` queued tasks for `worker`, capped by the capacity it registered with minus what
    /// it holds. Returns the tasks and whether the run has finished.
    pub fn lease(
        &self,
        worker: &str,
        max: u32,
        now: Instant,
    ) -> Result<(Vec<Arc<Task>>, bool), QueueError> {
        let mut s = self.lock();
        let s = &mut *s;
        let w = s
            .workers
            .get_mut(worker)
            .ok_or_else(|| QueueError::UnknownWorker(worker.to_owned()))?;
        w.last_seen = now;
        let room = w.capacity.saturating_sub(w.leased.len() as u32).min(max) as usize;
        let mut granted = Vec::with_capacity(room.min(s.queue.len()));
        while granted.len() < room {
            let Some(id) = s.queue.pop_front() else { break };
            let t = s.tasks.get_mut(&id).expect("queued tasks exist");
            t.phase = TaskPhase::Leased {
                worker: worker.to_owned(),
                deadline: now + self.rules.lease,
            };
            if !t.leased_to.iter().any(|w| w == worker) {
                t.leased_to.push(worker.to_owned());
            }
            w.leased.insert(id);
            granted.push(t.task.clone());
        }
        s.stats.dispatched += granted.len() as u64;
        Ok((granted, s.run_finished))
    }

    /// Records a worker's result for a task: its outcome, or the error that kept it from
    /// evaluating.
    pub fn report(
        &self,
        worker: &str,
        task_id: u64,
        result: Result<Outcome, String>,
        wall_seconds: f64,
    ) -> Result<Disposition, QueueError> {
        let mut s = self.lock();
        let s = &mut *s;
        if !s.issued_workers.contains(worker) {
            return Err(QueueError::UnknownWorker(worker.to_owned()));
        }
        let Some(t) = s.tasks.get_mut(&task_id) else {
            return if task_id != 0 && task_id <= s.highest_task {
                s.stats.duplicates += 1;
                Ok(Disposition::Duplicate)
            } else {
                Err(QueueError::UnknownTask(task_id))
            };
        };
        if !t.leased_to.iter().any(|w| w == worker) {
            return Err(QueueError::NotLeasedTo {
                task: task_id,
                worker: worker.to_owned(),
            });
        }
        if matches!(t.phase, TaskPhase::Done) {
            s.stats.duplicates += 1;
            return Ok(Disposition::Duplicate);
        }
        // Whatever happens next, this worker no longer holds the task.
        if let TaskPhase::Leased { worker: holder, .. } = &t.phase
            && let Some(w) = s.workers.get_mut(holder)
        {
            w.leased.remove(&task_id);
        }
        if let Some(w) = s.workers.get_mut(worker) {
            w.leased.remove(&task_id);
        }
        let slot = t.slot;
        let (completion, disposition) = match result {
            Ok(outcome) => (
                Completion {
                    slot,
                    outcome,
                    worker: match s.workers.get(worker) {
                        Some(w) => format!("{} ({worker})", w.name),
                        None => worker.to_owned(),
                    },
                    wall_seconds,
                },
                Disposition::Accepted,
            ),
            Err(error) => {
                s.stats.worker_errors += 1;
                let t = s.tasks.get_mut(&task_id).expect("checked above");
                warn!(worker, task = task_id, %error, "worker could not evaluate a task");
                t.errors.push(format!("{worker}: {error}"));
                s.noted_errors
                    .push((task_id, worker.to_owned(), error.clone()));
                if (t.errors.len() as u32) < self.rules.max_attempts {
                    t.phase = TaskPhase::Queued;
                    s.queue.push_front(task_id);
                    self.work.notify_waiters();
                    return Ok(Disposition::ErrorNoted);
                }
                warn!(
                    task = task_id,
                    attempts = t.errors.len(),
                    "task failed on every attempt: marked failed"
                );
                (
                    Completion {
                        slot,
                        outcome: Outcome::failed(Failure::Internal(format!(
                            "no worker could evaluate it ({} attempts): {}",
                            t.errors.len(),
                            t.errors.join("; ")
                        ))),
                        worker: "coordinator".into(),
                        wall_seconds: 0.0,
                    },
                    Disposition::ErrorNoted,
                )
            }
        };
        let t = s.tasks.get_mut(&task_id).expect("checked above");
        t.phase = TaskPhase::Done;
        s.stats.completed += 1;
        // The reporting worker has a free slot now: a lease of its that found it full may be
        // waiting for exactly this.
        self.work.notify_waiters();
        if let Some(tx) = &s.completions {
            // The search may have given up on the batch (shutdown); nothing to deliver to then.
            let _ = tx.send(completion);
        }
        Ok(disposition)
    }

    /// A worker is alive and still evaluating `active`: extend those leases. Returns the tasks of
    /// `active` it no longer holds, and whether the run has finished.
    pub fn heartbeat(
        &self,
        worker: &str,
        active: &[u64],
        now: Instant,
    ) -> Result<(Vec<u64>, bool), QueueError> {
        let mut s = self.lock();
        let s = &mut *s;
        let w = s
            .workers
            .get_mut(worker)
            .ok_or_else(|| QueueError::UnknownWorker(worker.to_owned()))?;
        w.last_seen = now;
        let mut revoked = Vec::new();
        for &id in active {
            match s.tasks.get_mut(&id).map(|t| &mut t.phase) {
                Some(TaskPhase::Leased {
                    worker: holder,
                    deadline,
                }) if holder == worker => *deadline = now + self.rules.lease,
                _ => revoked.push(id),
            }
        }
        Ok((revoked, s.run_finished))
    }

    /// A worker hands back leases it will not finish (it is shutting down).
    pub fn release(&self, worker: &str, ids: &[u64]) -> Result<u32, QueueError> {
        let mut s = self.lock();
        let s = &mut *s;
        let w = s
            .workers
            .get_mut(worker)
            .ok_or_else(|| QueueError::UnknownWorker(worker.to_owned()))?;
        let mut released = 0;
        for &id in ids.iter().rev() {
            if !w.leased.remove(&id) {
                continue;
            }
            if let Some(t) = s.tasks.get_mut(&id) {
                t.phase = TaskPhase::Queued;
                s.queue.push_front(id);
                released += 1;
            }
        }
        if released > 0 {
            self.work.notify_waiters();
        }
        Ok(released)
    }

    /// Returns expired leases and the leases of silent workers to the queue; drops silent workers.
    /// Called periodically by the server.
    pub fn reap(&self, now: Instant) {
        let mut s = self.lock();
        let s = &mut *s;
        let mut requeue = Vec::new();
        let timeout = self.rules.worker_timeout;
        s.workers.retain(|id, w| {
            let alive = now.saturating_duration_since(w.last_seen) < timeout;
            if !alive {
                warn!(worker = %id, name = %w.name, leases = w.leased.len(), "worker went silent: its leases go back to the queue");
                requeue.extend(w.leased.iter().copied());
            }
            alive
        });
        for (&id, t) in &s.tasks {
            if let TaskPhase::Leased { worker, deadline } = &t.phase
                && (*deadline <= now || !s.workers.contains_key(worker))
                && !requeue.contains(&id)
            {
                requeue.push(id);
            }
        }
        if requeue.is_empty() {
            return;
        }
        // Back to the front in task order, so re-dispatch order does not depend on hashing.
        requeue.sort_unstable();
        for &id in requeue.iter().rev() {
            let t = s.tasks.get_mut(&id).expect("leased tasks exist");
            if let TaskPhase::Leased { worker, .. } = &t.phase
                && let Some(w) = s.workers.get_mut(worker)
            {
                w.leased.remove(&id);
            }
            t.phase = TaskPhase::Queued;
            s.queue.push_front(id);
        }
        s.stats.expired_leases += requeue.len() as u64;
        info!(
            tasks = requeue.len(),
            "leases expired: tasks back in the queue"
        );
        self.work.notify_waiters();
    }

    /// Replaces the current batch with `tasks` (ids must increase) and returns the channel its
    /// completions arrive on, one per task, in the order they finish.
    pub fn submit(&self, tasks: Vec<Task>) -> Receiver<Completion> {
        let (tx, rx) = channel();
        let mut guard = self.lock();
        let s = &mut *guard;
        for w in s.workers.values_mut() {
            w.leased.clear();
        }
        s.tasks.clear();
        s.queue.clear();
        for (slot, task) in tasks.into_iter().enumerate() {
            let id = task.id.0;
            assert!(id > s.highest_task, "task ids increase across batches");
            s.highest_task = id;
            s.queue.push_back(id);
            s.tasks.insert(
                id,
                TaskState {
                    task: Arc::new(task),
                    slot,
                    phase: TaskPhase::Queued,
                    leased_to: Vec::new(),
                    errors: Vec::new(),
                },
            );
        }
        s.completions = Some(tx);
        drop(guard);
        self.work.notify_waiters();
        rx
    }

    /// Ends the run: leases answer `run_finished`, waiting leases return at once.
    pub fn finish(&self) {
        let mut s = self.lock();
        s.run_finished = true;
        s.queue.clear();
        s.completions = None;
        drop(s);
        self.work.notify_waiters();
    }

    /// Worker errors noted since the last call: (task id, worker id, message).
    pub fn take_noted_errors(&self) -> Vec<(u64, String, String)> {
        std::mem::take(&mut self.lock().noted_errors)
    }

    pub fn is_finished(&self) -> bool {
        self.lock().run_finished
    }

    pub fn stats(&self) -> QueueStats {
        let s = self.lock();
        QueueStats {
            workers: s.workers.len(),
            queued: s.queue.len(),
            leased: s.workers.values().map(|w| w.leased.len()).sum(),
            ..s.stats
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::TaskId;
    use amorph::genome::Genome;
    use amorph::voxel::GridDims;

    fn tasks(ids: std::ops::RangeInclusive<u64>) -> Vec<Task> {
        ids.map(|id| Task {
            id: TaskId(id),
            genome: Genome::default(),
            dims: GridDims::new(2, 2, 2),
        })
        .collect()
    }

    fn rules() -> QueueRules {
        QueueRules {
            lease: Duration::from_secs(10),
            heartbeat_interval: Duration::from_secs(1),
            worker_timeout: Duration::from_secs(3),
            max_attempts: 3,
        }
    }

    fn ok() -> Result<Outcome, String> {
        Ok(Outcome::failed(Failure::Empty))
    }

    fn ids(leased: &[Arc<Task>]) -> Vec<u64> {
        leased.iter().map(|t| t.id.0).collect()
    }

    #[test]
    fn leases_respect_capacity_and_task_order() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let w = q.register("a", 2, t0);
        let rx = q.submit(tasks(1..=5));
        assert_eq!(ids(&q.lease(&w, 8, t0).unwrap().0), [1, 2]);
        assert!(q.lease(&w, 8, t0).unwrap().0.is_empty(), "at capacity");
        assert_eq!(q.report(&w, 2, ok(), 0.1).unwrap(), Disposition::Accepted);
        assert_eq!(ids(&q.lease(&w, 8, t0).unwrap().0), [3]);
        assert_eq!(rx.try_recv().unwrap().slot, 1);
        assert_eq!(q.stats().leased, 2);
    }

    #[test]
    fn an_expired_lease_is_redispatched_and_the_late_report_counts_once() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let a = q.register("a", 1, t0);
        let b = q.register("b", 1, t0);
        let rx = q.submit(tasks(1..=1));
        assert_eq!(ids(&q.lease(&a, 1, t0).unwrap().0), [1]);
        // a heartbeats (stays registered) but never names the task: the lease runs out.
        let later = t0 + Duration::from_secs(11);
        q.heartbeat(&a, &[], later).unwrap();
        q.heartbeat(&b, &[], later).unwrap();
        q.reap(later);
        assert_eq!(ids(&q.lease(&b, 1, later).unwrap().0), [1]);
        assert_eq!(q.report(&a, 1, ok(), 1.0).unwrap(), Disposition::Accepted);
        assert_eq!(q.report(&b, 1, ok(), 1.0).unwrap(), Disposition::Duplicate);
        assert!(rx.try_recv().is_ok());
        assert!(rx.try_recv().is_err(), "exactly one completion");
        // b still thinks it holds task 1: the heartbeat tells it otherwise.
        assert_eq!(q.heartbeat(&b, &[1], later).unwrap().0, [1]);
    }

    #[test]
    fn heartbeats_keep_leases_and_silence_loses_them() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let a = q.register("a", 1, t0);
        q.submit(tasks(1..=1));
        q.lease(&a, 1, t0).unwrap();
        let mut now = t0;
        for _ in 0..30 {
            now += Duration::from_secs(1);
            assert!(q.heartbeat(&a, &[1], now).unwrap().0.is_empty());
            q.reap(now);
        }
        assert_eq!(
            q.stats().leased,
            1,
            "30 s of heartbeats outlast a 10 s lease"
        );
        q.reap(now + Duration::from_secs(4));
        assert_eq!(q.stats().workers, 0, "silent for longer than the timeout");
        assert_eq!(q.stats().queued, 1);
        assert_eq!(
            q.lease(&a, 1, now).unwrap_err(),
            QueueError::UnknownWorker(a.clone())
        );
    }

    #[test]
    fn reports_for_unknown_or_never_leased_tasks_are_refused() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let a = q.register("a", 4, t0);
        let b = q.register("b", 4, t0);
        q.submit(tasks(1..=2));
        q.lease(&a, 1, t0).unwrap();
        assert_eq!(
            q.report(&a, 99, ok(), 0.0),
            Err(QueueError::UnknownTask(99))
        );
        assert_eq!(q.report(&a, 0, ok(), 0.0), Err(QueueError::UnknownTask(0)));
        assert!(matches!(
            q.report(&b, 1, ok(), 0.0),
            Err(QueueError::NotLeasedTo { task: 1, .. })
        ));
        assert!(matches!(
            q.report(&a, 2, ok(), 0.0),
            Err(QueueError::NotLeasedTo { task: 2, .. })
        ));
        assert!(matches!(
            q.report("w9-forged", 1, ok(), 0.0),
            Err(QueueError::UnknownWorker(_))
        ));
        // Nothing above disturbed the legitimate lease.
        assert_eq!(q.report(&a, 1, ok(), 0.0).unwrap(), Disposition::Accepted);
    }

    #[test]
    fn a_task_failing_on_every_attempt_is_marked_failed_with_the_reasons() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let workers: Vec<_> = ["a", "b", "c"]
            .iter()
            .map(|n| q.register(n, 1, t0))
            .collect();
        let rx = q.submit(tasks(1..=1));
        for (i, w) in workers.iter().enumerate() {
            assert_eq!(ids(&q.lease(w, 1, t0).unwrap().0), [1]);
            let d = q.report(w, 1, Err(format!("boom {i}")), 0.0).unwrap();
            assert_eq!(d, Disposition::ErrorNoted);
            assert_eq!(
                rx.try_recv().is_ok(),
                i == 2,
                "a completion only at the last attempt"
            );
        }
        assert!(
            q.lease(&workers[0], 1, t0).unwrap().0.is_empty(),
            "not retried forever"
        );
        assert_eq!(q.stats().worker_errors, 3);
    }

    #[test]
    fn released_tasks_go_back_to_the_front() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let a = q.register("a", 2, t0);
        let b = q.register("b", 2, t0);
        q.submit(tasks(1..=4));
        q.lease(&a, 2, t0).unwrap();
        assert_eq!(q.release(&a, &[1, 2]).unwrap(), 2);
        assert_eq!(q.release(&a, &[1]).unwrap(), 0, "only what it holds");
        assert_eq!(ids(&q.lease(&b, 2, t0).unwrap().0), [1, 2]);
    }

    #[test]
    fn a_report_from_an_earlier_batch_is_a_duplicate_and_finish_ends_leases() {
        let q = TaskQueue::new(rules());
        let t0 = Instant::now();
        let a = q.register("a", 4, t0);
        q.submit(tasks(1..=2));
        q.lease(&a, 4, t0).unwrap();
        q.report(&a, 1, ok(), 0.0).unwrap();
        q.report(&a, 2, ok(), 0.0).unwrap();
        q.submit(tasks(3..=3));
        assert_eq!(q.report(&a, 2, ok(), 0.0).unwrap(), Disposition::Duplicate);
        q.finish();
        let (leased, finished) = q.lease(&a, 4, t0).unwrap();
        assert!(leased.is_empty() && finished);
    }
}
