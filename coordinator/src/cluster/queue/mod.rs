//! The task queue with leases: the coordinator's whole bookkeeping of who evaluates what.
//!
//! A synchronous state machine behind one mutex, with the time passed in, so every rule (lease
//! expiry, silent workers, duplicate and late reports, retries, shares) is tested without a
//! network. The gRPC service calls it; the search submits one batch at a time and collects its
//! completions from a channel as they arrive (so the run store records each one at once).
//!
//! Each task of the batch is in one phase (`task.rs`): **queued → leased → done | failed**, and
//! leased → queued when a lease lapses, its worker goes silent or hands it back, or the holder
//! reports an error. Done and failed are final: such a task is never leased again and sends
//! exactly one completion. Rules:
//! - Every call names a worker and carries the session secret its registration returned, bound
//!   to the principal (credential) that registered it (`crate::principal`); a worker id alone
//!   proves nothing.
//! - A lease lasts `lease` from when it is granted or last named in a heartbeat by its holder,
//!   and never longer than its lifetime; while other principals wait, a principal holds at most
//!   its fair share (`share.rs`).
//! - The first outcome reported for a task wins, even from a worker whose lease has lapsed (the
//!   evaluation is a pure function, so a late outcome is as good as any); later ones are
//!   duplicates and change nothing.
//! - A worker may report only tasks it was leased at some point, and answers each at most once.
//! - A worker's error (or a malformed outcome) is noted; the task is not leased to that voice
//!   again (an outside worker's voice is its principal's), and is marked failed only once
//!   `max_attempts` *different* voices have given errors, so one credential cannot fail a task
//!   however many workers it registers.
//! - A check task (`TaskId::is_check`, verification of an outside worker's outcome) is leased
//!   only to a principal that may check the claimant's; one no live worker may take is handed to
//!   the coordinator itself (`orphans`), so a check never waits for a worker that cannot come.
//! - A quarantined principal (a credential caught in a lie), or under the shared token the one
//!   registration caught, loses its leases and every later call is refused; trusted workers (the
//!   coordinator's own) are never checked.

mod rules;
mod share;
mod task;
mod view;
mod worker_calls;

#[cfg(test)]
#[path = "tests/principals.rs"]
mod principals;
#[cfg(test)]
#[path = "tests/properties.rs"]
mod properties;
#[cfg(test)]
mod tests;

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use amorph::task::Outcome;
use tracing::{info, warn};

use crate::evaluator::{Claimant, Completion, Origin, Task};
use crate::ids::{TaskId, WorkerId};
use crate::principal::{Principal, Sessions};
pub use rules::{Disposition, MAX_WORKERS, NotedError, QueueError, QueueRules, QueueStats};
use task::{Phase, TaskState, Voice};
pub use view::WorkerView;

/// Who makes a call: a worker id, the principal the call's credential proves, and the session
/// secret the worker's registration returned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Caller {
    pub worker: WorkerId,
    pub principal: Principal,
    pub session: String,
}

#[derive(Debug)]
struct WorkerState {
    name: String,
    principal: Principal,
    capacity: u32,
    last_seen: Instant,
    leased: HashSet<TaskId>,
    /// In this process (or trusted by config): its outcomes are final without a check.
    trusted: bool,
    /// When it last asked for work or delivered an outcome (a worker between the two is at work).
    last_asked: Instant,
    /// Slots its last lease call with room left unfilled (it waits for work while this is
    /// above 0 and that call is recent).
    wants: u32,
    /// A lease or heartbeat has answered it that the run finished.
    told_finished: bool,
}

impl WorkerState {
    fn voice(&self, id: WorkerId) -> Voice {
        if self.trusted {
            Voice::Worker(id)
        } else {
            Voice::Principal(self.principal.clone())
        }
    }
}

#[derive(Debug)]
struct State {
    workers: HashMap<WorkerId, WorkerState>,
    next_worker: u64,
    /// The current batch, by id.
    tasks: BTreeMap<TaskId, TaskState>,
    /// Exactly the tasks in phase `Queued`, leased lowest id first.
    queued: BTreeSet<TaskId>,
    /// Tasks of earlier batches and the workers they were leased to, so a late report is told
    /// apart as a duplicate (it was leased to the reporter) or a forgery (it was not).
    earlier: HashMap<TaskId, Box<[WorkerId]>>,
    /// Highest task id ever submitted, of search tasks and of check tasks.
    highest_task: [Option<TaskId>; 2],
    /// Workers caught disagreeing with a check: every later call of theirs is refused.
    quarantined: HashSet<WorkerId>,
    /// Credentials caught the same way: every call and registration under them is refused.
    quarantined_principals: HashSet<Principal>,
    /// Grant-to-report times of the last accepted reports, for the lease lifetime.
    lease_times: share::LeaseTimes,
    completions: Option<Sender<Completion>>,
    noted_errors: Vec<NotedError>,
    run_finished: bool,
    stats: QueueStats,
}

/// The queue shared by the gRPC service, the reaper and the search.
#[derive(Debug)]
pub struct TaskQueue {
    rules: QueueRules,
    /// Distinguishes this coordinator process's worker ids from a previous one's (after a resume).
    tag: u32,
    sessions: Sessions,
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
            tag: ((nanos ^ (u128::from(std::process::id()) << 20)) & 0xff_ffff) as u32,
            sessions: Sessions::new(),
            state: Mutex::new(State {
                workers: HashMap::new(),
                next_worker: 0,
                tasks: BTreeMap::new(),
                queued: BTreeSet::new(),
                earlier: HashMap::new(),
                highest_task: [None, None],
                quarantined: HashSet::new(),
                quarantined_principals: HashSet::new(),
                lease_times: share::LeaseTimes::default(),
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
        // A panic while holding the lock would be a bug in this module; the state is still
        // consistent between transitions, so carry on rather than poison every later call.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Waits until work may be available (a batch was submitted, a lease came back, the run
    /// ended). Create the future *before* checking the queue so no wake-up is missed.
    pub fn work_notified(&self) -> tokio::sync::futures::Notified<'_> {
        self.work.notified()
    }

    /// Returns expired leases and the leases of silent workers to the queue; drops silent workers.
    /// Called periodically by the server.
    pub fn reap(&self, now: Instant) {
        let mut guard = self.lock();
        let s = &mut *guard;
        let timeout = self.rules.worker_timeout;
        let silent: Vec<WorkerId> = s
            .workers
            .iter()
            .filter(|(_, w)| now.saturating_duration_since(w.last_seen) >= timeout)
            .map(|(&id, _)| id)
            .collect();
        let mut requeue = BTreeSet::new();
        for id in &silent {
            let w = &s.workers[id];
            warn!(worker = %id, name = %w.name, leases = w.leased.len(), "worker went silent: its leases go back to the queue");
            requeue.extend(w.leased.iter().copied());
        }
        for (&id, t) in &s.tasks {
            if let Phase::Leased { deadline, .. } = t.phase
                && deadline <= now
            {
                requeue.insert(id);
            }
        }
        for &id in &requeue {
            s.requeue_or_fail(id, self.rules.max_attempts, true);
        }
        for id in &silent {
            s.workers.remove(id);
        }
        s.warn_unservable();
        if requeue.is_empty() {
            return;
        }
        s.stats.expired_leases += requeue.len() as u64;
        info!(
            tasks = requeue.len(),
            "leases expired: tasks back in the queue"
        );
        drop(guard);
        self.work.notify_waiters();
    }

    /// Replaces the current batch with `tasks` (ids must increase) and returns the channel its
    /// completions arrive on, one per task, in the order they finish.
    pub fn submit(&self, tasks: Vec<Task>) -> Receiver<Completion> {
        self.submit_checks(tasks.into_iter().map(|t| (t, None)).collect())
    }

    /// [`TaskQueue::submit`] for tasks each of which may check a claim of one principal: such a
    /// task is leased only to a principal that may check that one.
    pub fn submit_checks(&self, tasks: Vec<(Task, Option<Principal>)>) -> Receiver<Completion> {
        let (tx, rx) = channel();
        let mut guard = self.lock();
        let s = &mut *guard;
        for w in s.workers.values_mut() {
            w.leased.clear();
        }
        for (id, t) in std::mem::take(&mut s.tasks) {
            s.earlier.insert(id, t.leased_to.into_boxed_slice());
        }
        s.queued.clear();
        for (slot, (task, checks)) in tasks.into_iter().enumerate() {
            let id = task.id;
            let highest = &mut s.highest_task[usize::from(id.is_check())];
            assert!(
                highest.is_none_or(|h| id > h),
                "task ids increase across batches"
            );
            *highest = Some(id);
            s.queued.insert(id);
            s.tasks.insert(id, TaskState::new(task, slot, checks));
        }
        s.completions = Some(tx);
        drop(guard);
        self.work.notify_waiters();
        rx
    }

    /// Queued tasks the coordinator evaluates itself: check tasks that came back from a lease
    /// (their holder went silent, gave them back or held them past their lease), and any task
    /// some voice gave an error for, or any check, that no worker at work may take (its voice
    /// failed it, its principal may not check the claim, or there is none): they neither hold a
    /// lease nor have asked for work within a lease's length (a worker may be alive and never
    /// ask). So no worker can hold a check back for longer than one lease, and a task one
    /// principal refuses to evaluate waits for no one. The outcomes go to
    /// [`TaskQueue::finish_here`].
    pub fn orphans(&self, now: Instant) -> Vec<Arc<Task>> {
        let s = self.lock();
        let working = |w: &WorkerState| {
            w.capacity > 0
                && (!w.leased.is_empty()
                    || now.saturating_duration_since(w.last_asked) < self.rules.lease)
        };
        s.queued
            .iter()
            .map(|id| &s.tasks[id])
            // A task a trusted worker failed would fail here too (its memory budget, say).
            .filter(|t| {
                t.task.id.is_check()
                    || (!t.errors.is_empty()
                        && t.errors
                            .iter()
                            .all(|(v, _)| matches!(v, Voice::Principal(_))))
            })
            .filter(|t| {
                (t.task.id.is_check() && !t.leased_to.is_empty())
                    || !s
                        .workers
                        .iter()
                        .any(|(&id, w)| working(w) && t.may_take(id, w))
            })
            .map(|t| t.task.clone())
            .collect()
    }

    /// An outcome the coordinator computed itself for a task of the batch (see
    /// [`TaskQueue::orphan_checks`]); a task already final keeps its outcome.
    pub fn finish_here(&self, task: TaskId, outcome: Outcome, wall_seconds: f64) {
        let mut s = self.lock();
        if s.tasks.get(&task).is_some_and(|t| !t.phase.is_final()) {
            s.finish(
                task,
                outcome,
                "coordinator".into(),
                Origin::Trusted,
                wall_seconds,
            );
        }
    }

    /// Refuses every later call of the claimant and returns its leases to the queue: it was
    /// caught reporting an outcome a check contradicted. Under a credential the whole credential
    /// is quarantined (it answers for its workers); under the shared token, which honest workers
    /// hold too, the one registration.
    pub fn quarantine(&self, liar: &Claimant) {
        let mut guard = self.lock();
        let s = &mut *guard;
        let caught: Vec<WorkerId> = if liar.principal.answers_for_its_workers() {
            if !s.quarantined_principals.insert(liar.principal.clone()) {
                return;
            }
            s.workers
                .iter()
                .filter(|(_, w)| w.principal == liar.principal)
                .map(|(&id, _)| id)
                .collect()
        } else {
            if liar.principal.is_local() || !s.quarantined.insert(liar.worker) {
                return;
            }
            vec![liar.worker]
        };
        for worker in caught {
            let held: Vec<TaskId> = s
                .workers
                .get(&worker)
                .map(|w| w.leased.iter().copied().collect())
                .unwrap_or_default();
            for id in held {
                s.requeue_or_fail(id, self.rules.max_attempts, true);
            }
            s.workers.remove(&worker);
        }
        warn!(worker = %liar.worker, principal = %liar.principal, "quarantined: its leases go back to the queue and its calls are refused");
        drop(guard);
        self.work.notify_waiters();
    }

    /// Whether the claimant, or its credential, is in this process's quarantine.
    pub fn is_quarantined(&self, claimant: &Claimant) -> bool {
        let s = self.lock();
        s.quarantined.contains(&claimant.worker)
            || s.quarantined_principals.contains(&claimant.principal)
    }

    /// Ends the run: leases answer `run_finished`, waiting leases return at once.
    pub fn finish(&self) {
        let mut s = self.lock();
        s.run_finished = true;
        s.completions = None;
        drop(s);
        self.work.notify_waiters();
    }

    /// Worker errors noted since the last call.
    pub fn take_noted_errors(&self) -> Vec<NotedError> {
        std::mem::take(&mut self.lock().noted_errors)
    }

    pub fn is_finished(&self) -> bool {
        self.lock().run_finished
    }

    /// After [`TaskQueue::finish`]: whether every registered worker has been told, so the server
    /// may close. A worker that never calls again stops counting once the reaper drops it, a
    /// `worker_timeout` after its last call (a quarantined one is dropped at once).
    pub fn everyone_told(&self) -> bool {
        let s = self.lock();
        s.run_finished && s.workers.values().all(|w| w.told_finished)
    }

    pub fn stats(&self) -> QueueStats {
        let s = self.lock();
        QueueStats {
            workers: s.workers.len(),
            queued: s.queued.len(),
            leased: s.workers.values().map(|w| w.leased.len()).sum(),
            ..s.stats
        }
    }
}
