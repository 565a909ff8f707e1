//! One task's life in the queue and the only code that moves it between phases:
//! queued → leased → done | failed, and leased → queued. Every transition keeps the queue's
//! indexes (the queued set, each worker's leased set) in step with the phases, and the two final
//! phases send the task's one completion.

use std::sync::Arc;
use std::time::Instant;

use amorph::outcome::Failure;
use amorph::task::Outcome;
use tracing::warn;

use super::State;
use crate::evaluator::{Completion, Origin, Task};
use crate::ids::{TaskId, WorkerId};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    Queued,
    Leased {
        worker: WorkerId,
        /// When the lease lapses unless its holder heartbeats.
        deadline: Instant,
        /// When it lapses whatever the holder says (`QueueRules::max_lease` after the grant).
        expires: Instant,
    },
    /// An outcome was accepted: final.
    Done,
    /// `max_attempts` different workers gave errors: final.
    Failed,
}

impl Phase {
    pub(super) fn is_final(self) -> bool {
        matches!(self, Phase::Done | Phase::Failed)
    }
}

#[derive(Debug)]
pub(super) struct TaskState {
    pub(super) task: Arc<Task>,
    pub(super) slot: usize,
    pub(super) phase: Phase,
    /// Every worker the task was ever leased to: only they may report it.
    pub(super) leased_to: Vec<WorkerId>,
    /// Errors, at most one per worker.
    pub(super) errors: Vec<(WorkerId, String)>,
    /// The worker this task is kept from: a check is never evaluated by its claimant.
    pub(super) excluded: Option<WorkerId>,
    /// Whether "no live worker can take it" was logged since the last change of workers.
    unservable_logged: bool,
}

impl TaskState {
    pub(super) fn new(task: Task, slot: usize, excluded: Option<WorkerId>) -> Self {
        Self {
            task: Arc::new(task),
            slot,
            phase: Phase::Queued,
            leased_to: Vec::new(),
            errors: Vec::new(),
            excluded,
            unservable_logged: false,
        }
    }

    pub(super) fn failed_by(&self, worker: WorkerId) -> bool {
        self.errors.iter().any(|(w, _)| *w == worker)
    }

    /// Whether `worker` may be leased this task: it has not failed it and is not its claimant.
    pub(super) fn may_take(&self, worker: WorkerId) -> bool {
        !self.failed_by(worker) && self.excluded != Some(worker)
    }
}

impl State {
    /// Queued → leased to `worker` from `now`.
    pub(super) fn grant(
        &mut self,
        id: TaskId,
        worker: WorkerId,
        now: Instant,
        rules: &super::QueueRules,
    ) -> Arc<Task> {
        let expires = now + rules.max_lease;
        let deadline = (now + rules.lease).min(expires);
        let t = self.tasks.get_mut(&id).expect("granted tasks exist");
        debug_assert_eq!(t.phase, Phase::Queued);
        self.queued.remove(&id);
        t.phase = Phase::Leased {
            worker,
            deadline,
            expires,
        };
        if !t.leased_to.contains(&worker) {
            t.leased_to.push(worker);
        }
        if let Some(w) = self.workers.get_mut(&worker) {
            w.leased.insert(id);
        }
        t.task.clone()
    }

    /// Takes the task out of whatever index its current phase puts it in.
    fn leave_phase(&mut self, id: TaskId) {
        let t = &self.tasks[&id];
        match t.phase {
            Phase::Queued => {
                self.queued.remove(&id);
            }
            Phase::Leased { worker, .. } => {
                if let Some(w) = self.workers.get_mut(&worker) {
                    w.leased.remove(&id);
                }
            }
            Phase::Done | Phase::Failed => unreachable!("final phases are never left"),
        }
    }

    /// Leased → queued, or → failed when enough different workers have given up on it.
    pub(super) fn requeue_or_fail(&mut self, id: TaskId, max_attempts: u32) {
        let Some(t) = self.tasks.get(&id) else { return };
        if !matches!(t.phase, Phase::Leased { .. }) {
            return;
        }
        self.leave_phase(id);
        let t = self.tasks.get_mut(&id).expect("checked above");
        t.phase = Phase::Queued;
        t.unservable_logged = false;
        self.queued.insert(id);
        self.fail_if_exhausted(id, max_attempts);
    }

    /// Queued → failed once `max_attempts` different workers gave errors.
    pub(super) fn fail_if_exhausted(&mut self, id: TaskId, max_attempts: u32) {
        let t = &self.tasks[&id];
        if t.phase != Phase::Queued || (t.errors.len() as u32) < max_attempts {
            return;
        }
        warn!(task = %id, attempts = t.errors.len(), "task failed on every attempt: marked failed");
        let reasons: Vec<String> = t.errors.iter().map(|(w, e)| format!("{w}: {e}")).collect();
        let outcome = Outcome::failed(Failure::Internal(format!(
            "no worker could evaluate it ({} workers): {}",
            t.errors.len(),
            reasons.join("; ")
        )));
        self.leave_phase(id);
        self.tasks.get_mut(&id).expect("checked above").phase = Phase::Failed;
        self.complete(id, outcome, "coordinator".into(), Origin::GaveUp, 0.0);
    }

    /// Queued or leased → done with the first accepted outcome.
    pub(super) fn finish(
        &mut self,
        id: TaskId,
        outcome: Outcome,
        by: String,
        origin: Origin,
        wall_seconds: f64,
    ) {
        self.leave_phase(id);
        self.tasks.get_mut(&id).expect("reported tasks exist").phase = Phase::Done;
        self.complete(id, outcome, by, origin, wall_seconds);
    }

    /// `Err(Quarantined)` for a worker caught disagreeing with a check.
    pub(super) fn refuse_quarantined(&self, worker: WorkerId) -> Result<(), super::QueueError> {
        if self.quarantined.contains(&worker) {
            return Err(super::QueueError::Quarantined(worker));
        }
        Ok(())
    }

    fn complete(
        &mut self,
        id: TaskId,
        outcome: Outcome,
        worker: String,
        origin: Origin,
        wall_seconds: f64,
    ) {
        self.stats.completed += 1;
        if let Some(tx) = &self.completions {
            // The search may have given up on the batch (shutdown); nothing to deliver to then.
            let _ = tx.send(Completion {
                slot: self.tasks[&id].slot,
                outcome,
                worker,
                wall_seconds,
                origin,
            });
        }
    }

    /// Logs, once per task until the workers change, a queued task that every live worker has
    /// already failed: it waits for a worker that has not, rather than letting the same workers
    /// decide its failure.
    pub(super) fn warn_unservable(&mut self) {
        if self.workers.is_empty() {
            return;
        }
        for &id in &self.queued {
            let t = self.tasks.get_mut(&id).expect("queued tasks exist");
            // A check no one may take goes to the coordinator itself (`orphan_checks`).
            if !t.unservable_logged
                && !id.is_check()
                && self.workers.keys().all(|&w| !t.may_take(w))
            {
                t.unservable_logged = true;
                warn!(task = %id, failed_by = t.errors.len(), "every connected worker failed this task: it waits for another worker");
            }
        }
    }

    /// The invariants every transition keeps, checked by the property tests after every step.
    #[cfg(test)]
    pub(super) fn check(&self, max_attempts: u32) -> Result<(), String> {
        use std::collections::BTreeSet;
        let queued: BTreeSet<TaskId> = self
            .tasks
            .iter()
            .filter(|(_, t)| t.phase == Phase::Queued)
            .map(|(&id, _)| id)
            .collect();
        if queued != self.queued {
            return Err(format!(
                "queued index {:?} != phases {queued:?}",
                self.queued
            ));
        }
        for (&id, t) in &self.tasks {
            let mut seen = BTreeSet::new();
            if !t.errors.iter().all(|(w, _)| seen.insert(*w)) {
                return Err(format!("{id}: two errors from one worker"));
            }
            if t.phase == Phase::Failed && (t.errors.len() as u32) < max_attempts {
                return Err(format!("{id} failed after {} workers", t.errors.len()));
            }
            if let Phase::Leased { worker, .. } = t.phase
                && !self
                    .workers
                    .get(&worker)
                    .is_some_and(|w| w.leased.contains(&id))
            {
                return Err(format!("{id} leased to {worker}, who does not hold it"));
            }
        }
        for (&wid, w) in &self.workers {
            if self.quarantined.contains(&wid) {
                return Err(format!("{wid} is quarantined yet still registered"));
            }
            if w.leased.len() > w.capacity as usize {
                return Err(format!("{wid} holds {} > capacity", w.leased.len()));
            }
            for id in &w.leased {
                match self.tasks.get(id).map(|t| t.phase) {
                    Some(Phase::Leased { worker, .. }) if worker == wid => {}
                    other => return Err(format!("{wid} holds {id} in phase {other:?}")),
                }
            }
        }
        Ok(())
    }
}
