//! The coordinator's own workers (`cluster.local_workers`): evaluators inside its process that take
//! work from the same task queue as `worker --connect` processes, under the same leases,
//! heartbeats and reaping, so a run on local workers alone follows the rules a cluster does. They
//! skip the wire (nothing to convert, nothing to authenticate, no loopback TLS) and their outcomes
//! are final without a check, being computed here.

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Instant;

use amorph::dynamics::EvaluationThreads;
use amorph::task::memory;
use amorph::task::{Outcome, Scene};
use tokio::sync::watch;
use tokio::task::JoinSet;
use tracing::{debug, info, warn};

use super::queue::{Caller, QueueError, TaskQueue};
use crate::evaluator::Task;
use crate::ids::{TaskId, WorkerId};
use crate::principal::Principal;

/// What one local worker did, for the log.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LocalSummary {
    pub evaluated: u64,
    /// Leases handed back because the run was stopped.
    pub released: u64,
}

/// One local worker: its registration and what it is evaluating.
#[derive(Debug)]
pub struct LocalWorker {
    queue: Arc<TaskQueue>,
    scene: Arc<Scene>,
    name: String,
    threads: usize,
    /// Bytes one evaluation may take (the worker's share of the machine, split by its threads).
    budget_per_evaluation: u64,
    /// The threads each evaluation runs on (`cluster.threads_per_evaluation`).
    shared: Arc<EvaluationThreads>,
}

type Evaluated = (WorkerId, TaskId, Result<Outcome, String>, f64);

impl LocalWorker {
    pub fn new(
        queue: Arc<TaskQueue>,
        scene: Arc<Scene>,
        name: String,
        threads: usize,
        budget: u64,
    ) -> Self {
        let threads = threads.max(1);
        Self {
            queue,
            scene,
            name,
            threads,
            budget_per_evaluation: budget / threads as u64,
            shared: Arc::default(),
        }
    }

    /// Runs each evaluation on `threads`, which share its simulation (the same bits).
    pub fn sharing_evaluations(self, threads: EvaluationThreads) -> Self {
        Self {
            shared: Arc::new(threads),
            ..self
        }
    }

    /// Works until the run finishes (`run_finished` on a lease or heartbeat) or `stop` is set,
    /// when it hands its leases back at once: a stopped run keeps only what was finished.
    pub async fn run(self, mut stop: watch::Receiver<bool>) -> Result<LocalSummary, QueueError> {
        let mut summary = LocalSummary::default();
        let mut id = self.register()?;
        let mut running: JoinSet<Evaluated> = JoinSet::new();
        let mut active: BTreeSet<TaskId> = BTreeSet::new();
        let mut heartbeat = tokio::time::interval(self.queue.rules().heartbeat_interval);
        heartbeat.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            if *stop.borrow() {
                let held: Vec<TaskId> = active.iter().copied().collect();
                summary.released += u64::from(self.queue.leave(&id, &held).unwrap_or(0));
                info!(worker = %id.worker, released = summary.released, "local worker stopped");
                return Ok(summary);
            }
            // Registered before the lease, so work queued between the two still wakes us.
            let notified = self.queue.work_notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            let free = self.threads.saturating_sub(active.len());
            if free > 0 {
                let leased = match self.queue.lease(&id, free as u32, Instant::now()) {
                    Err(QueueError::UnknownWorker(_)) => {
                        (id, active) = (self.rejoin(&id)?, BTreeSet::new());
                        continue;
                    }
                    other => other?,
                };
                let (tasks, finished) = leased;
                if finished {
                    return Ok(summary);
                }
                for task in tasks {
                    self.start(&id, &task, &mut running, &mut active);
                }
            }
            let room = self.threads > active.len();
            tokio::select! {
                Some(joined) = running.join_next() => {
                    let (lease, task, result, wall) = match joined {
                        Ok(done) => done,
                        // The evaluation catches its own panics; a failed join is a runtime
                        // shutting down, and the lease expires on its own.
                        Err(e) => { warn!(error = %e, "local evaluation lost"); continue; }
                    };
                    if lease != id.worker || !active.remove(&task) {
                        continue; // leased under an earlier registration: the queue has moved on
                    }
                    summary.evaluated += 1;
                    self.report(&id, task, result, wall);
                }
                () = &mut notified, if room => {}
                _ = heartbeat.tick() => {
                    let held: Vec<TaskId> = active.iter().copied().collect();
                    match self.queue.heartbeat(&id, &held, Instant::now()) {
                        Ok((_, true)) => return Ok(summary),
                        Ok((_, false)) => {}
                        Err(QueueError::UnknownWorker(_)) => {
                            (id, active) = (self.rejoin(&id)?, BTreeSet::new());
                        }
                        Err(e) => return Err(e),
                    }
                }
                changed = stop.changed() => {
                    if changed.is_err() {
                        // The job dropped its stop sender: nobody can stop us any more, so stop.
                        let held: Vec<TaskId> = active.iter().copied().collect();
                        let _ = self.queue.leave(&id, &held);
                        return Ok(summary);
                    }
                }
            }
        }
    }

    fn register(&self) -> Result<Caller, QueueError> {
        self.queue.register(
            &self.name,
            self.threads as u32,
            Principal::Local,
            true,
            std::time::Instant::now(),
        )
    }

    /// A report the queue refuses (a batch that moved on) loses nothing: the task was done or
    /// re-leased elsewhere.
    fn report(&self, id: &Caller, task: TaskId, result: Result<Outcome, String>, wall: f64) {
        match self.queue.report(id, task, result, wall, Instant::now()) {
            Ok(disposition) => debug!(%task, ?disposition, "reported"),
            Err(e) => warn!(%task, error = %e, "local outcome not taken"),
        }
    }

    /// The reaper dropped this worker (its heartbeats were starved past `worker_timeout`): its
    /// leases went back to the queue, so it registers again with nothing held.
    fn rejoin(&self, old: &Caller) -> Result<Caller, QueueError> {
        warn!(worker = %old.worker, name = %self.name, "local worker was dropped as silent: registering again");
        self.register()
    }

    /// Puts a leased task on a blocking thread; one over the memory budget is refused at once as
    /// this worker's error, and goes to another worker (or fails after `max_attempts`).
    fn start(
        &self,
        id: &Caller,
        task: &Arc<Task>,
        running: &mut JoinSet<Evaluated>,
        active: &mut BTreeSet<TaskId>,
    ) {
        if let Err(error) = memory::check(&self.scene, task.dims, self.budget_per_evaluation) {
            warn!(task = %task.id, %error, "cannot evaluate a leased task");
            self.report(id, task.id, Err(error.to_string()), 0.0);
            return;
        }
        active.insert(task.id);
        let (task, scene, shared) = (task.clone(), self.scene.clone(), self.shared.clone());
        let id = id.worker;
        running.spawn_blocking(move || {
            let started = Instant::now();
            let outcome = shared.run(|| scene.evaluate(&task.genome, task.dims));
            (id, task.id, Ok(outcome), started.elapsed().as_secs_f64())
        });
    }
}

#[cfg(test)]
mod tests;
