//! What a worker may ask of the queue: to register, to lease tasks, to report outcomes, to
//! heartbeat its leases, and to hand them back or leave. Each call first proves who makes it (a
//! worker this queue issued, with its session secret, under the credential that registered it,
//! not quarantined) before it touches a task (the rules in `mod.rs`).

use std::collections::{BTreeSet, HashSet};
use std::sync::Arc;
use std::time::Instant;

use amorph::task::Outcome;
use tracing::{info, warn};

use super::task::{Phase, Voice};
use super::{Caller, Disposition, MAX_WORKERS, QueueError, State, TaskQueue, WorkerState};
use crate::evaluator::{Claimant, Origin, Task};
use crate::ids::{TaskId, WorkerId};
use crate::principal::Principal;

impl TaskQueue {
    /// Registers a worker of `principal`; `name` must already be cleaned of control characters.
    /// A `trusted` worker's outcomes are final without a check. An outside worker's capacity is
    /// capped at `max_capacity`; at most `max_workers_per_credential` are registered per principal
    /// (over it, the principal's longest-idle registration that holds no lease and is not waiting
    /// for work makes room, else the call is refused) and [`MAX_WORKERS`] in all, so
    /// registrations cannot grow the coordinator's memory without bound or crowd out another
    /// principal. Returns the worker's id and session secret.
    pub fn register(
        &self,
        name: &str,
        capacity: u32,
        principal: Principal,
        trusted: bool,
        now: Instant,
    ) -> Result<Caller, QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        if s.quarantined_principals.contains(&principal) {
            warn!(name, %principal, "registration refused: the credential is quarantined");
            return Err(QueueError::Quarantined(WorkerId {
                serial: 0,
                tag: self.tag,
            }));
        }
        let mut capacity = capacity;
        if !trusted {
            capacity = capacity.min(self.rules.max_capacity);
            self.make_room(s, &principal, now)?;
            if s.workers.values().filter(|w| !w.trusted).count() >= MAX_WORKERS {
                warn!(
                    name,
                    "registration refused: {MAX_WORKERS} outside workers already registered"
                );
                return Err(QueueError::TooManyWorkers);
            }
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
                principal: principal.clone(),
                capacity,
                last_seen: now,
                leased: HashSet::new(),
                trusted,
                last_asked: now,
                wants: 0,
                told_finished: false,
            },
        );
        info!(worker = %id, name, %principal, capacity, trusted, "worker registered");
        Ok(Caller {
            worker: id,
            session: self.sessions.secret(id, &principal),
            principal,
        })
    }

    /// Below the per-credential limit, or one idle registration of `principal` dropped.
    fn make_room(
        &self,
        s: &mut State,
        principal: &Principal,
        now: Instant,
    ) -> Result<(), QueueError> {
        let limit = self.rules.max_workers_per_credential;
        let mine = || s.workers.iter().filter(|(_, w)| w.principal == *principal);
        if mine().count() < limit {
            return Ok(());
        }
        let idle = mine()
            .filter(|(_, w)| w.leased.is_empty() && !w.waiting(now))
            .min_by_key(|&(&id, w)| (w.last_asked, id))
            .map(|(&id, _)| id);
        let Some(idle) = idle else {
            warn!(%principal, limit, "registration refused: every registration of this credential is at work");
            return Err(QueueError::TooManyForCredential {
                principal: principal.to_string(),
                limit,
            });
        };
        s.workers.remove(&idle);
        s.stats.evicted += 1;
        info!(worker = %idle, %principal, "idle registration dropped to make room for a new one of its credential");
        Ok(())
    }

    /// Whether `caller` is a worker this process issued, with its own session secret, and not
    /// quarantined. A worker the reaper dropped still passes (its late outcomes count).
    fn authenticate(&self, s: &State, caller: &Caller) -> Result<(), QueueError> {
        let w = caller.worker;
        if w.tag != self.tag || w.serial < 1 || w.serial > s.next_worker {
            return Err(QueueError::UnknownWorker(w));
        }
        if !self.sessions.verify(w, &caller.principal, &caller.session) {
            warn!(worker = %w, principal = %caller.principal, "call with a wrong session secret refused");
            return Err(QueueError::BadSession(w));
        }
        s.refuse_quarantined(w, &caller.principal)
    }

    /// The registered worker making an authenticated call, marked as just heard from.
    fn seen<'a>(
        &self,
        s: &'a mut State,
        caller: &Caller,
        now: Instant,
    ) -> Result<&'a mut WorkerState, QueueError> {
        self.authenticate(s, caller)?;
        let w = s
            .workers
            .get_mut(&caller.worker)
            .ok_or(QueueError::UnknownWorker(caller.worker))?;
        w.last_seen = now;
        Ok(w)
    }

    /// Up to `max` queued tasks for the caller, capped by its capacity minus what it holds and by
    /// its principal's share while others wait, skipping tasks its voice failed, checks its
    /// principal may not make, and tasks it gave back while another principal waits for them.
    /// Returns the tasks and whether the run has finished.
    pub fn lease(
        &self,
        caller: &Caller,
        max: u32,
        now: Instant,
    ) -> Result<(Vec<Arc<Task>>, bool), QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        let worker = caller.worker;
        let finished = s.run_finished;
        let w = self.seen(s, caller, now)?;
        if finished {
            w.told_finished = true;
            return Ok((Vec::new(), true));
        }
        let room = w.capacity.saturating_sub(w.leased.len() as u32).min(max);
        // Asking for nothing is not asking: only a call with room counts as a worker at work.
        if room > 0 {
            w.last_asked = now;
        }
        let allowed = s.allowance(worker, room, now) as usize;
        let me = &s.workers[&worker];
        let chosen: Vec<TaskId> = s
            .queued
            .iter()
            .filter(|&&id| {
                let t = &s.tasks[&id];
                t.may_take(worker, me) && !s.goes_to_another_first(t, &me.principal, now)
            })
            .take(allowed)
            .copied()
            .collect();
        let backups = self.backups(s, worker, allowed - chosen.len(), now);
        let granted: Vec<Arc<Task>> = chosen
            .into_iter()
            .chain(backups)
            .map(|id| s.grant(id, worker, now, &self.rules))
            .collect();
        if let Some(w) = s.workers.get_mut(&worker) {
            w.wants = room - granted.len() as u32;
        }
        s.stats.dispatched += granted.len() as u64;
        let held_back = (allowed as u32) < room && !s.queued.is_empty();
        drop(guard);
        if held_back {
            // Its share held this worker back for others who wait: wake them to take theirs.
            self.work.notify_waiters();
        }
        Ok((granted, false))
    }

    /// Up to `n` tasks held by other principals' outside workers for longer than the backup time
    /// that `worker` may take, oldest grant first, taken back from their holders (whose outcome
    /// still counts if it comes first) and requeued for `worker` to be granted.
    fn backups(&self, s: &mut State, worker: WorkerId, n: usize, now: Instant) -> Vec<TaskId> {
        if n == 0 {
            return Vec::new();
        }
        let me = &s.workers[&worker];
        let after = s.backup_after(&self.rules);
        // Only what other principals' outside workers hold: the common case, one principal or
        // local workers alone, looks at no task.
        let mut held: Vec<(Instant, TaskId)> = s
            .workers
            .values()
            .filter(|h| !h.trusted && h.principal != me.principal)
            .flat_map(|h| h.leased.iter())
            .filter_map(|id| {
                let t = &s.tasks[id];
                match t.phase {
                    Phase::Leased { granted, .. }
                        if now.saturating_duration_since(granted) > after
                            && t.may_take(worker, me) =>
                    {
                        Some((granted, *id))
                    }
                    _ => None,
                }
            })
            .collect();
        held.sort_unstable();
        let taken: Vec<TaskId> = held.into_iter().take(n).map(|(_, id)| id).collect();
        for &id in &taken {
            s.requeue_or_fail(id, self.rules.max_attempts, true);
        }
        let taken: Vec<TaskId> = taken
            .into_iter()
            .filter(|id| s.tasks[id].phase == Phase::Queued)
            .collect();
        if !taken.is_empty() {
            s.stats.expired_leases += taken.len() as u64;
            info!(tasks = taken.len(), %worker, "tasks held past the backup time taken over by a waiting worker");
        }
        taken
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
        caller: &Caller,
        task: TaskId,
        result: Result<Outcome, String>,
        wall_seconds: f64,
        now: Instant,
    ) -> Result<Disposition, QueueError> {
        let mut results = self.report_all(caller, [(task, result, wall_seconds)], now)?;
        results.pop().expect("one result per task")
    }

    /// [`TaskQueue::report`] for several tasks of one caller, proven once: one disposition or
    /// refusal per task, in order; `Err` when the caller itself is refused.
    pub fn report_all(
        &self,
        caller: &Caller,
        results: impl IntoIterator<Item = (TaskId, Result<Outcome, String>, f64)>,
        now: Instant,
    ) -> Result<Vec<Result<Disposition, QueueError>>, QueueError> {
        let mut guard = self.lock();
        self.authenticate(&guard, caller)?;
        let dispositions = results
            .into_iter()
            .map(|(task, result, wall)| self.record(&mut guard, caller, task, result, wall, now))
            .collect();
        // The reporting worker may have a free slot now, or a task may be queued again: a
        // waiting lease may be waiting for exactly this.
        drop(guard);
        self.work.notify_waiters();
        Ok(dispositions)
    }

    /// One result of an authenticated caller.
    fn record(
        &self,
        s: &mut State,
        caller: &Caller,
        task: TaskId,
        result: Result<Outcome, String>,
        wall_seconds: f64,
        now: Instant,
    ) -> Result<Disposition, QueueError> {
        let worker = caller.worker;
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
        let (by, trusted) = match s.workers.get(&worker) {
            Some(w) => (format!("{} ({worker})", w.name), w.trusted),
            None => (worker.to_string(), caller.principal.is_local()),
        };
        let voice = if trusted {
            Voice::Worker(worker)
        } else {
            Voice::Principal(caller.principal.clone())
        };
        if t.phase.is_final() || t.failed_by(&voice) {
            s.stats.duplicates += 1;
            return Ok(Disposition::Duplicate);
        }
        let holder = match t.phase {
            Phase::Leased {
                worker: holder,
                granted,
                ..
            } if holder == worker => Some(granted),
            _ => None,
        };
        let disposition = match result {
            Ok(outcome) => {
                if let Some(w) = s.workers.get_mut(&worker) {
                    // A worker whose evaluation outlasted a lease has not asked for a lease's
                    // length, yet it is at work: without this, a check queued meanwhile
                    // counts as one no worker may take, and the coordinator makes it.
                    w.last_asked = now;
                }
                if let Some(granted) = holder {
                    s.lease_times.measure(granted, now);
                }
                let origin = if trusted {
                    Origin::Trusted
                } else {
                    Origin::Claim(Claimant {
                        worker,
                        principal: caller.principal.clone(),
                    })
                };
                s.finish(task, outcome, by, origin, wall_seconds);
                Disposition::Accepted
            }
            Err(error) => {
                s.stats.worker_errors += 1;
                warn!(%worker, %task, %error, "worker could not evaluate a task");
                t.errors.push((voice, error.clone()));
                s.noted_errors.push((task, worker, error));
                // A former holder's error leaves the current holder's lease alone: only the
                // holder's own error, or a lease coming back, decides what happens next.
                match (holder, s.tasks[&task].phase) {
                    (Some(_), _) => s.requeue_or_fail(task, self.rules.max_attempts, false),
                    (None, Phase::Queued) => s.fail_if_exhausted(task, self.rules.max_attempts),
                    _ => {}
                }
                Disposition::ErrorNoted
            }
        };
        Ok(disposition)
    }

    /// A worker is alive and still evaluating `active`: extend those leases (never past their
    /// lifetime). Returns the tasks of `active` it no longer holds, and whether the run has
    /// finished.
    pub fn heartbeat(
        &self,
        caller: &Caller,
        active: &[TaskId],
        now: Instant,
    ) -> Result<(Vec<TaskId>, bool), QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        let finished = s.run_finished;
        self.seen(s, caller, now)?.told_finished |= finished;
        let mut revoked = Vec::new();
        for &id in active {
            match s.tasks.get_mut(&id).map(|t| &mut t.phase) {
                Some(Phase::Leased {
                    worker: holder,
                    deadline,
                    expires,
                    ..
                }) if *holder == caller.worker => {
                    *deadline = (now + self.rules.lease).min(*expires);
                }
                _ => revoked.push(id),
            }
        }
        Ok((revoked, finished))
    }

    /// A worker hands back leases it will not finish (it is shutting down).
    pub fn release(&self, caller: &Caller, ids: &[TaskId]) -> Result<u32, QueueError> {
        let mut guard = self.lock();
        let s = &mut *guard;
        self.authenticate(s, caller)?;
        let w = s
            .workers
            .get(&caller.worker)
            .ok_or(QueueError::UnknownWorker(caller.worker))?;
        let held: BTreeSet<TaskId> = ids
            .iter()
            .filter(|&&id| w.leased.contains(&id))
            .copied()
            .collect();
        for &id in &held {
            s.requeue_or_fail(id, self.rules.max_attempts, true);
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
    pub fn leave(&self, caller: &Caller, ids: &[TaskId]) -> Result<u32, QueueError> {
        let released = self.release(caller, ids)?;
        self.lock().workers.remove(&caller.worker);
        Ok(released)
    }
}
