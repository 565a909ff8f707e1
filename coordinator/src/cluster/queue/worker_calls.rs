//! What a worker may ask of the queue: to register, to lease tasks, to report outcomes, to
//! heartbeat its leases, and to hand them back or leave. Each call checks that the worker is one
//! this queue issued and not quarantined before it touches a task (the rules in `mod.rs`).

use std::collections::{BTreeSet, HashSet};
use std::sync::Arc;
use std::time::Instant;

use amorph::task::Outcome;
use tracing::{info, warn};

use super::task::Phase;
use super::{Disposition, MAX_WORKERS, QueueError, TaskQueue, WorkerState, seen};
use crate::evaluator::{Origin, Task};
use crate::ids::{TaskId, WorkerId};

impl TaskQueue {
    /// Registers a worker; `name` must already be cleaned of control characters. A `trusted`
    /// worker's outcomes are final without a check. At most [`MAX_WORKERS`] outside workers are
    /// registered at once (a silent one is dropped after `worker_timeout`), so registrations
    /// cannot grow the coordinator's memory without bound.
    pub fn register(
        &self,
        name: &str,
        capacity: u32,
        trusted: bool,
        now: Instant,
    ) -> Result<WorkerId, QueueError> {
        let mut s = self.lock();
        if !trusted && s.workers.values().filter(|w| !w.trusted).count() >= MAX_WORKERS {
            warn!(
                name,
                "registration refused: {MAX_WORKERS} outside workers already registered"
            );
            return Err(QueueError::TooManyWorkers);
        }
        s.next_worker += 1;
        let id = WorkerId {
            serial: s.next_worker,
            tag: self.tag,
        };
        s.workers.insert(
            id,
            WorkerState {
                name: name.to_owned(),
                capacity,
                last_seen: now,
                leased: HashSet::new(),
                trusted,
                last_asked: now,
                told_finished: false,
            },
        );
        info!(worker = %id, name, capacity, trusted, "worker registered");
        Ok(id)
    }

    /// Up to `max` queued tasks for `worker`, capped by the capacity it registered with minus what
    /// it holds, skipping tasks it already failed. Returns the tasks and whether the run has
    /// finished.
    pub fn lease(
        &self,
        worker: WorkerId,
        max: u32,
        now: Instant,
    ) -> Result<(Vec<Arc<Task>>, bool), QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        s.refuse_quarantined(worker)?;
        let w = seen(&mut s.workers, worker, now)?;
        if s.run_finished {
            w.told_finished = true;
            return Ok((Vec::new(), true));
        }
        let room = w.capacity.saturating_sub(w.leased.len() as u32).min(max) as usize;
        // Asking for nothing is not asking: only a call with room counts as a worker at work.
        if room > 0 {
            w.last_asked = now;
        }
        let chosen: Vec<TaskId> = s
            .queued
            .iter()
            .filter(|&&id| s.tasks[&id].may_take(worker))
            .take(room)
            .copied()
            .collect();
        let granted: Vec<Arc<Task>> = chosen
            .into_iter()
            .map(|id| s.grant(id, worker, now, &self.rules))
            .collect();
        s.stats.dispatched += granted.len() as u64;
        Ok((granted, false))
    }

    /// The resolution a task asks for, while the queue holds it (to check a reported outcome
    /// against what its scene can produce at that resolution).
    pub fn task_dims(&self, task: TaskId) -> Option<amorph::voxel::GridDims> {
        self.lock().tasks.get(&task).map(|t| t.task.dims)
    }

    /// Records a worker's result for a task: its outcome, or the error that kept it from
    /// evaluating (`error` must already be cleaned of control characters).
    pub fn report(
        &self,
        worker: WorkerId,
        task: TaskId,
        result: Result<Outcome, String>,
        wall_seconds: f64,
        now: Instant,
    ) -> Result<Disposition, QueueError> {
        let mut guard = self.lock();
        if !self.issued(&guard, worker) {
            return Err(QueueError::UnknownWorker(worker));
        }
        let s = &mut *guard;
        s.refuse_quarantined(worker)?;
        let Some(t) = s.tasks.get_mut(&task) else {
            return match s.earlier.get(&task) {
                Some(leased_to) if leased_to.contains(&worker) => {
                    s.stats.duplicates += 1;
                    Ok(Disposition::Duplicate)
                }
                Some(_) => Err(QueueError::NotLeasedTo { task, worker }),
                None => Err(QueueError::UnknownTask(task)),
            };
        };
        if !t.leased_to.contains(&worker) {
            return Err(QueueError::NotLeasedTo { task, worker });
        }
        if t.phase.is_final() || t.failed_by(worker) {
            s.stats.duplicates += 1;
            return Ok(Disposition::Duplicate);
        }
        let disposition = match result {
            Ok(outcome) => {
                let (by, trusted) = match s.workers.get_mut(&worker) {
                    Some(w) => {
                        // A worker whose evaluation outlasted a lease has not asked for a lease's
                        // length, yet it is at work: without this, a check queued meanwhile
                        // counts as one no worker may take, and the coordinator makes it.
                        w.last_asked = now;
                        (format!("{} ({worker})", w.name), w.trusted)
                    }
                    None => (worker.to_string(), false),
                };
                let origin = if trusted {
                    Origin::Trusted
                } else {
                    Origin::Claim(worker)
                };
                s.finish(task, outcome, by, origin, wall_seconds);
                Disposition::Accepted
            }
            Err(error) => {
                s.stats.worker_errors += 1;
                warn!(%worker, %task, %error, "worker could not evaluate a task");
                t.errors.push((worker, error.clone()));
                s.noted_errors.push((task, worker, error));
                // A former holder's error leaves the current holder's lease alone: only the
                // holder's own error, or a lease coming back, decides what happens next.
                let phase = s.tasks[&task].phase;
                match phase {
                    Phase::Leased { worker: holder, .. } if holder == worker => {
                        s.requeue_or_fail(task, self.rules.max_attempts);
                    }
                    Phase::Queued => s.fail_if_exhausted(task, self.rules.max_attempts),
                    _ => {}
                }
                Disposition::ErrorNoted
            }
        };
        // The reporting worker may have a free slot now, or the task may be queued again: a
        // waiting lease may be waiting for exactly this.
        drop(guard);
        self.work.notify_waiters();
        Ok(disposition)
    }

    /// A worker is alive and still evaluating `active`: extend those leases. Returns the tasks of
    /// `active` it no longer holds, and whether the run has finished.
    pub fn heartbeat(
        &self,
        worker: WorkerId,
        active: &[TaskId],
        now: Instant,
    ) -> Result<(Vec<TaskId>, bool), QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        s.refuse_quarantined(worker)?;
        seen(&mut s.workers, worker, now)?.told_finished |= s.run_finished;
        let mut revoked = Vec::new();
        for &id in active {
            match s.tasks.get_mut(&id).map(|t| &mut t.phase) {
                Some(Phase::Leased {
                    worker: holder,
                    deadline,
                    expires,
                }) if *holder == worker => *deadline = (now + self.rules.lease).min(*expires),
                _ => revoked.push(id),
            }
        }
        Ok((revoked, s.run_finished))
    }

    /// A worker hands back leases it will not finish (it is shutting down).
    pub fn release(&self, worker: WorkerId, ids: &[TaskId]) -> Result<u32, QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        s.refuse_quarantined(worker)?;
        let w = s
            .workers
            .get(&worker)
            .ok_or(QueueError::UnknownWorker(worker))?;
        let held: BTreeSet<TaskId> = ids
            .iter()
            .filter(|&&id| w.leased.contains(&id))
            .copied()
            .collect();
        for &id in &held {
            s.requeue_or_fail(id, self.rules.max_attempts);
        }
        drop(guard);
        if !held.is_empty() {
            self.work.notify_waiters();
        }
        Ok(held.len() as u32)
    }

    /// A worker shuts down for good: it hands back `ids` (as [`TaskQueue::release`]) and is
    /// forgotten at once, so neither the reaper (which would warn that it went silent) nor the
    /// end of a finished run (which waits until every registered worker has heard of it) waits a
    /// `worker_timeout` for it.
    pub fn leave(&self, worker: WorkerId, ids: &[TaskId]) -> Result<u32, QueueError> {
        let released = self.release(worker, ids)?;
        self.lock().workers.remove(&worker);
        Ok(released)
    }
}
