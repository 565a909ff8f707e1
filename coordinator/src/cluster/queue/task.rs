//! One task's life in the queue and the only code that moves it between phases:
//! queued → leased → done | failed, and leased → queued. Every transition keeps the queue's
//! indexes (the queued set, each worker's leased set) in step with the phases, and the two final
//! phases send the task's one completion.

use std::sync::Arc;
use std::time::Instant;

use amorph::outcome::Failure;
use amorph::task::Outcome;
use tracing::warn;

use super::{State, WorkerState};
use crate::evaluator::{Completion, Origin, Task};
use crate::ids::{TaskId, WorkerId};
use crate::principal::Principal;

/// Whose errors count as one: a trusted worker speaks for itself, an outside worker for its
/// principal, so one credential cannot fail a task by registering several times.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) enum Voice {
    Worker(WorkerId),
    Principal(Principal),
}

impl std::fmt::Display for Voice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Voice::Worker(w) => write!(f, "{w}"),
            Voice::Principal(p) => write!(f, "{p}"),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Phase {
    Queued,
    Leased {
        worker: WorkerId,
        /// When it was granted, to measure how long evaluations take.
        granted: Instant,
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
    /// Errors, at most one per voice.
    pub(super) errors: Vec<(Voice, String)>,
    /// The principal whose claim this task checks: it may be evaluated only by a principal that
    /// may check that one ([`Principal::may_be_checked_by`]).
    pub(super) checks: Option<Principal>,
    /// Principals whose lease on it lapsed or who handed it back: it goes to another first.
    pub(super) returned_by: Vec<Principal>,
    /// Whether "no live worker can take it" was logged since the last change of workers.
    unservable_logged: bool,
}

impl TaskState {
    pub(super) fn new(task: Task, slot: usize, checks: Option<Principal>) -> Self {
        Self {
            task: Arc::new(task),
            slot,
            phase: Phase::Queued,
            leased_to: Vec::new(),
            errors: Vec::new(),
            checks,
            returned_by: Vec::new(),
            unservable_logged: false,
        }
    }

    pub(super) fn failed_by(&self, voice: &Voice) -> bool {
        self.errors.iter().any(|(v, _)| v == voice)
    }

    /// Whether worker `id` may be leased this task: its voice has not failed it, and for a check,
    /// its principal may check the claimant's.
    pub(super) fn may_take(&self, id: WorkerId, w: &WorkerState) -> bool {
        !self.failed_by(&w.voice(id))
            && self
                .checks
                .as_ref()
                .is_none_or(|claimant| claimant.may_be_checked_by(&w.principal))
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
        // The coordinator's own workers never hoard: only `max_lease` bounds them.
        let trusted = self.workers.get(&worker).is_some_and(|w| w.trusted);
        let lifetime = if trusted {
            rules.max_lease
        } else {
            self.lease_lifetime(rules)
        };
        let expires = now + lifetime;
        let deadline = (now + rules.lease).min(expires);
        let t = self.tasks.get_mut(&id).expect("granted tasks exist");
        debug_assert_eq!(t.phase, Phase::Queued);
        self.queued.remove(&id);
        t.phase = Phase::Leased {
            worker,
            granted: now,
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

    /// Leased → queued, or → failed when enough different voices have given up on it. A task
    /// whose lease lapsed or was handed back (`returned`) goes to another principal first.
    pub(super) fn requeue_or_fail(&mut self, id: TaskId, max_attempts: u32, returned: bool) {
        let Some(t) = self.tasks.get(&id) else { return };
        let Phase::Leased { worker, .. } = t.phase else {
            return;
        };
        let holder = self.workers.get(&worker).map(|w| w.principal.clone());
        self.leave_phase(id);
        let t = self.tasks.get_mut(&id).expect("checked above");
        if returned
            && let Some(p) = holder
            && !p.is_local()
            && !t.returned_by.contains(&p)
        {
            t.returned_by.push(p);
        }
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
        let reasons: Vec<String> = t.errors.iter().map(|(v, e)| format!("{v}: {e}")).collect();
        let outcome = Outcome::failed(Failure::Internal(format!(
            "no worker could evaluate it ({} principals): {}",
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

    /// `Err(Quarantined)` for a worker caught disagreeing with a check, or one whose credential
    /// was.
    pub(super) fn refuse_quarantined(
        &self,
        worker: WorkerId,
        principal: &Principal,
    ) -> Result<(), super::QueueError> {
        if self.quarantined.contains(&worker) || self.quarantined_principals.contains(principal) {
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
            // A check no one may take goes to the coordinator itself (`orphans`).
            if !t.unservable_logged
                && !id.is_check()
                && self.workers.iter().all(|(&id, w)| !t.may_take(id, w))
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
            let mut seen = std::collections::HashSet::new();
            if !t.errors.iter().all(|(v, _)| seen.insert(v.clone())) {
                return Err(format!("{id}: two errors from one voice"));
            }
            if t.phase == Phase::Failed && (t.errors.len() as u32) < max_attempts {
                return Err(format!("{id} failed after {} voices", t.errors.len()));
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
            if self.quarantined.contains(&wid) || self.quarantined_principals.contains(&w.principal)
            {
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
