//! The queue's rules one by one, with the time passed in.

use super::*;
use amorph::genome::Genome;
use amorph::outcome::Failure;
use amorph::voxel::GridDims;
use std::time::Duration;

pub(super) fn tasks(ids: std::ops::RangeInclusive<u64>) -> Vec<Task> {
    ids.map(|id| Task {
        id: TaskId(id),
        genome: Genome::default(),
        dims: GridDims::new(2, 2, 2),
    })
    .collect()
}

pub(super) fn rules() -> QueueRules {
    QueueRules {
        lease: Duration::from_secs(10),
        heartbeat_interval: Duration::from_secs(1),
        worker_timeout: Duration::from_secs(3),
        max_attempts: 3,
        max_lease: Duration::from_secs(60),
        ..QueueRules::default()
    }
}

/// An outside worker under a credential of its own (named after it).
pub(super) fn outside(
    q: &TaskQueue,
    name: &str,
    capacity: u32,
    now: Instant,
) -> Result<Caller, QueueError> {
    q.register(
        name,
        capacity,
        Principal::Credential(name.into()),
        false,
        now,
    )
}

pub(super) fn claimant(c: &Caller) -> Claimant {
    Claimant {
        worker: c.worker,
        principal: c.principal.clone(),
    }
}

pub(super) fn ok() -> Result<Outcome, String> {
    Ok(Outcome::failed(Failure::Empty))
}

pub(super) fn ids(leased: &[Arc<Task>]) -> Vec<u64> {
    leased.iter().map(|t| t.id.0).collect()
}

const T1: TaskId = TaskId(1);
const T2: TaskId = TaskId(2);

#[test]
fn leases_respect_capacity_and_task_order() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let w = outside(&q, "a", 2, t0).unwrap();
    let rx = q.submit(tasks(1..=5));
    assert_eq!(ids(&q.lease(&w, 8, t0).unwrap().0), [1, 2]);
    assert!(q.lease(&w, 8, t0).unwrap().0.is_empty(), "at capacity");
    assert_eq!(
        q.report(&w, T2, ok(), 0.1, t0).unwrap(),
        Disposition::Accepted
    );
    assert_eq!(ids(&q.lease(&w, 8, t0).unwrap().0), [3]);
    assert_eq!(rx.try_recv().unwrap().slot, 1);
    assert_eq!(q.stats().leased, 2);
}

#[test]
fn an_expired_lease_is_redispatched_and_the_late_report_counts_once() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 1, t0).unwrap();
    let b = outside(&q, "b", 1, t0).unwrap();
    let rx = q.submit(tasks(1..=1));
    assert_eq!(ids(&q.lease(&a, 1, t0).unwrap().0), [1]);
    // a heartbeats (stays registered) but never names the task: the lease runs out.
    let later = t0 + Duration::from_secs(11);
    q.heartbeat(&a, &[], later).unwrap();
    q.heartbeat(&b, &[], later).unwrap();
    q.reap(later);
    assert_eq!(ids(&q.lease(&b, 1, later).unwrap().0), [1]);
    assert_eq!(
        q.report(&a, T1, ok(), 1.0, later).unwrap(),
        Disposition::Accepted
    );
    assert_eq!(
        q.report(&b, T1, ok(), 1.0, later).unwrap(),
        Disposition::Duplicate
    );
    assert!(rx.try_recv().is_ok());
    assert!(rx.try_recv().is_err(), "exactly one completion");
    // b still thinks it holds task 1: the heartbeat tells it otherwise.
    assert_eq!(q.heartbeat(&b, &[T1], later).unwrap().0, [T1]);
}

/// A late report for a re-queued task is final: the task leaves the queue, so it is never leased
/// again and no second (possibly forged) outcome can replace the first.
#[test]
fn a_late_report_after_expiry_is_final_and_never_leased_again() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 1, t0).unwrap();
    let b = outside(&q, "b", 1, t0).unwrap();
    let rx = q.submit(tasks(1..=1));
    q.lease(&a, 1, t0).unwrap();
    let later = t0 + Duration::from_secs(11);
    q.heartbeat(&a, &[], later).unwrap();
    q.heartbeat(&b, &[], later).unwrap();
    q.reap(later);
    assert_eq!(
        q.report(&a, T1, ok(), 1.0, later).unwrap(),
        Disposition::Accepted
    );
    assert!(
        q.lease(&b, 1, later).unwrap().0.is_empty(),
        "done: never leased again"
    );
    assert_eq!(
        rx.try_recv().unwrap().outcome,
        Outcome::failed(Failure::Empty)
    );
    assert!(rx.try_recv().is_err(), "exactly one completion");
    assert_eq!(q.stats().queued, 0);
}

/// Errors repeated by one worker for one task (as three in one `Report`) count once: one worker
/// cannot fail a task alone, and the task is not leased again to the worker that failed it.
#[test]
fn errors_repeated_by_one_worker_do_not_fail_a_task() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 1, t0).unwrap();
    let b = outside(&q, "b", 1, t0).unwrap();
    let rx = q.submit(tasks(1..=1));
    q.lease(&a, 1, t0).unwrap();
    assert_eq!(
        q.report(&a, T1, Err("nan".into()), 0.0, t0).unwrap(),
        Disposition::ErrorNoted
    );
    for _ in 0..2 {
        assert_eq!(
            q.report(&a, T1, Err("nan".into()), 0.0, t0).unwrap(),
            Disposition::Duplicate,
            "a worker answers a task once"
        );
    }
    assert!(rx.try_recv().is_err(), "one worker cannot fail a task");
    assert!(
        q.lease(&a, 1, t0).unwrap().0.is_empty(),
        "not leased again to the worker that failed it"
    );
    assert_eq!(ids(&q.lease(&b, 1, t0).unwrap().0), [1]);
    assert_eq!(
        q.report(&b, T1, ok(), 0.0, t0).unwrap(),
        Disposition::Accepted
    );
    assert_eq!(
        rx.try_recv().unwrap().outcome,
        Outcome::failed(Failure::Empty)
    );
    assert!(rx.try_recv().is_err());
}

/// A worker that was leased a task once cannot take it from its current holder by reporting an
/// error for it.
#[test]
fn an_error_from_a_former_holder_leaves_the_current_lease_alone() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 1, t0).unwrap();
    let b = outside(&q, "b", 1, t0).unwrap();
    q.submit(tasks(1..=1));
    q.lease(&a, 1, t0).unwrap();
    q.release(&a, &[T1]).unwrap();
    q.lease(&b, 1, t0).unwrap();
    assert_eq!(
        q.report(&a, T1, Err("forged".into()), 0.0, t0).unwrap(),
        Disposition::ErrorNoted
    );
    assert!(
        q.heartbeat(&b, &[T1], t0).unwrap().0.is_empty(),
        "b keeps its lease"
    );
    assert_eq!(q.stats().queued, 0);
    assert_eq!(
        q.report(&b, T1, ok(), 0.0, t0).unwrap(),
        Disposition::Accepted
    );
}

#[test]
fn heartbeats_keep_leases_and_silence_loses_them() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 1, t0).unwrap();
    q.submit(tasks(1..=1));
    q.lease(&a, 1, t0).unwrap();
    let mut now = t0;
    for _ in 0..30 {
        now += Duration::from_secs(1);
        assert!(q.heartbeat(&a, &[T1], now).unwrap().0.is_empty());
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
        QueueError::UnknownWorker(a.worker)
    );
}

#[test]
fn reports_for_unknown_or_never_leased_tasks_are_refused() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 4, t0).unwrap();
    let b = outside(&q, "b", 4, t0).unwrap();
    q.submit(tasks(1..=2));
    q.lease(&a, 1, t0).unwrap();
    assert_eq!(
        q.report(&a, TaskId(99), ok(), 0.0, t0),
        Err(QueueError::UnknownTask(TaskId(99)))
    );
    assert_eq!(
        q.report(&a, TaskId(0), ok(), 0.0, t0),
        Err(QueueError::UnknownTask(TaskId(0)))
    );
    assert_eq!(
        q.report(&b, T1, ok(), 0.0, t0),
        Err(QueueError::NotLeasedTo {
            task: T1,
            worker: b.worker
        })
    );
    assert_eq!(
        q.report(&a, T2, ok(), 0.0, t0),
        Err(QueueError::NotLeasedTo {
            task: T2,
            worker: a.worker
        })
    );
    let forged = Caller {
        worker: WorkerId {
            serial: 9,
            tag: a.worker.tag,
        },
        ..a.clone()
    };
    assert_eq!(
        q.report(&forged, T1, ok(), 0.0, t0),
        Err(QueueError::UnknownWorker(forged.worker))
    );
    let other_process = Caller {
        worker: WorkerId {
            tag: a.worker.tag ^ 1,
            ..a.worker
        },
        ..a.clone()
    };
    assert_eq!(
        q.report(&other_process, T1, ok(), 0.0, t0),
        Err(QueueError::UnknownWorker(other_process.worker))
    );
    // b knows a's id (ids are names) but not its secret; nor does a's secret pass under b's
    // credential.
    for stolen in [
        Caller {
            session: b.session.clone(),
            ..a.clone()
        },
        Caller {
            principal: b.principal.clone(),
            ..a.clone()
        },
    ] {
        assert_eq!(
            q.report(&stolen, T1, ok(), 0.0, t0),
            Err(QueueError::BadSession(a.worker))
        );
        assert_eq!(
            q.release(&stolen, &[T1]),
            Err(QueueError::BadSession(a.worker))
        );
    }
    // Nothing above disturbed the legitimate lease.
    assert_eq!(
        q.report(&a, T1, ok(), 0.0, t0).unwrap(),
        Disposition::Accepted
    );
}

#[test]
fn a_task_failing_on_three_different_workers_is_marked_failed_with_the_reasons() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let workers: Vec<_> = ["a", "b", "c"]
        .iter()
        .map(|n| outside(&q, n, 1, t0).unwrap())
        .collect();
    let rx = q.submit(tasks(1..=1));
    for (i, w) in workers.iter().enumerate() {
        assert_eq!(ids(&q.lease(w, 1, t0).unwrap().0), [1]);
        let d = q.report(w, T1, Err(format!("boom {i}")), 0.0, t0).unwrap();
        assert_eq!(d, Disposition::ErrorNoted);
        assert_eq!(
            rx.try_recv().is_ok(),
            i == 2,
            "a completion only at the third worker's error"
        );
    }
    let d = outside(&q, "d", 1, t0).unwrap();
    assert!(
        q.lease(&d, 1, t0).unwrap().0.is_empty(),
        "a failed task is never leased again"
    );
    assert_eq!(q.stats().worker_errors, 3);
    assert_eq!(q.take_noted_errors().len(), 3);
}

#[test]
fn released_tasks_go_back_to_the_front() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 2, t0).unwrap();
    let b = outside(&q, "b", 2, t0).unwrap();
    q.submit(tasks(1..=4));
    q.lease(&a, 2, t0).unwrap();
    assert_eq!(q.release(&a, &[T1, T2]).unwrap(), 2);
    assert_eq!(q.release(&a, &[T1]).unwrap(), 0, "only what it holds");
    assert_eq!(ids(&q.lease(&b, 2, t0).unwrap().0), [1, 2]);
}

/// A report for a task of an earlier batch that was never leased to the reporter is refused as a
/// task the worker never had, not answered as a duplicate.
#[test]
fn an_earlier_batch_tells_duplicates_from_never_leased_reports() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a = outside(&q, "a", 4, t0).unwrap();
    let b = outside(&q, "b", 4, t0).unwrap();
    q.submit(tasks(1..=2));
    q.lease(&a, 4, t0).unwrap();
    q.report(&a, T1, ok(), 0.0, t0).unwrap();
    q.report(&a, T2, ok(), 0.0, t0).unwrap();
    q.submit(tasks(3..=3));
    assert_eq!(
        q.report(&a, T2, ok(), 0.0, t0).unwrap(),
        Disposition::Duplicate
    );
    assert_eq!(
        q.report(&b, T2, ok(), 0.0, t0),
        Err(QueueError::NotLeasedTo {
            task: T2,
            worker: b.worker
        })
    );
    q.finish();
    let (leased, finished) = q.lease(&a, 4, t0).unwrap();
    assert!(leased.is_empty() && finished);
}

/// A lease ends `max_lease` after its grant (before any evaluation is measured) however often
/// its holder names it in a heartbeat, so a worker cannot hoard tasks; a late outcome from the
/// hoarder would still count if it came first.
#[test]
fn heartbeats_cannot_keep_a_lease_past_its_lifetime() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let hoarder = outside(&q, "hoarder", 2, t0).unwrap();
    let honest = outside(&q, "honest", 2, t0).unwrap();
    q.submit(tasks(1..=2));
    q.lease(&hoarder, 2, t0).unwrap();
    let mut now = t0;
    while now < t0 + Duration::from_secs(59) {
        now += Duration::from_secs(1);
        assert!(q.heartbeat(&hoarder, &[T1, T2], now).unwrap().0.is_empty());
        q.heartbeat(&honest, &[], now).unwrap();
        q.reap(now);
    }
    assert_eq!(q.stats().leased, 2, "within its lifetime");
    now += Duration::from_secs(1);
    q.heartbeat(&hoarder, &[T1, T2], now).unwrap();
    q.heartbeat(&honest, &[], now).unwrap();
    q.reap(now);
    assert_eq!(q.stats().queued, 2, "past its lifetime");
    assert_eq!(ids(&q.lease(&honest, 2, now).unwrap().0), [1, 2]);
    assert_eq!(q.heartbeat(&hoarder, &[T1, T2], now).unwrap().0, [T1, T2]);
}

pub(super) fn check_task(n: u64) -> Task {
    Task {
        id: TaskId(TaskId::FIRST_CHECK + n),
        genome: Genome::default(),
        dims: GridDims::new(2, 2, 2),
    }
}

/// A check of a worker's claim is never evaluated by that worker; once no other worker may take
/// it, the coordinator takes it (`orphans`), so a check never waits for a worker that cannot
/// come. Outcomes say whose word they are.
#[test]
fn a_check_is_kept_from_its_claimant_and_orphaned_when_no_one_else_may_take_it() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let claimant = outside(&q, "claimant", 4, t0).unwrap();
    let rx = q.submit(tasks(1..=1));
    q.lease(&claimant, 1, t0).unwrap();
    q.report(&claimant, T1, ok(), 0.1, t0).unwrap();
    assert_eq!(
        rx.try_recv().unwrap().origin,
        Origin::Claim(super::tests::claimant(&claimant))
    );

    let rx = q.submit_checks(vec![(check_task(0), Some(claimant.principal.clone()))]);
    assert!(
        q.lease(&claimant, 4, t0).unwrap().0.is_empty(),
        "kept from its claimant"
    );
    let orphans = q.orphans(t0);
    assert_eq!(orphans.len(), 1, "no other worker: the coordinator's");
    let other = q.register("other", 1, Principal::Local, true, t0).unwrap();
    assert!(q.orphans(t0).is_empty(), "another worker may take it now");
    let later = t0 + rules().lease;
    assert_eq!(
        q.orphans(later).len(),
        1,
        "unless it has not asked for work for a lease's length"
    );
    q.heartbeat(&other, &[], later).unwrap();
    assert_eq!(q.orphans(later).len(), 1, "a heartbeat is not asking");
    q.lease(&claimant, 1, later).unwrap();
    assert_eq!(q.orphans(later).len(), 1, "nor is the claimant's asking");
    assert!(q.lease(&other, 0, later).unwrap().0.is_empty());
    assert_eq!(
        q.orphans(later).len(),
        1,
        "asking for nothing is not asking"
    );
    assert_eq!(q.lease(&other, 1, later).unwrap().0.len(), 1);
    assert!(q.orphans(later).is_empty(), "taken");
    assert_eq!(q.release(&other, &[orphans[0].id]), Ok(1));
    assert_eq!(
        q.orphans(later).len(),
        1,
        "back from a lease: the coordinator's"
    );
    assert_eq!(
        q.lease(&other, 1, later).unwrap().0.len(),
        1,
        "unless a worker is quicker"
    );
    q.report(&other, orphans[0].id, ok(), 0.1, later).unwrap();
    let done = rx.try_recv().unwrap();
    assert_eq!(done.origin, Origin::Trusted, "a trusted worker's outcome");
    // The coordinator's own late outcome changes nothing: the first is final.
    q.finish_here(
        orphans[0].id,
        Outcome::failed(Failure::Internal("x".into())),
        0.0,
    );
    assert!(rx.try_recv().is_err());
}

/// A worker whose evaluation outlasted a lease (a 20³ robot takes longer than `lease_ms`) has not
/// asked for work since it leased, yet delivering its outcome shows it at work: a check queued
/// meanwhile is its to take, not the coordinator's.
#[test]
fn delivering_an_outcome_counts_as_asking_for_work() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let claimant = outside(&q, "claimant", 1, t0).unwrap();
    let slow = outside(&q, "slow", 1, t0).unwrap();
    let rx = q.submit(tasks(1..=2));
    q.lease(&claimant, 1, t0).unwrap();
    q.lease(&slow, 1, t0).unwrap();
    q.report(&claimant, T1, ok(), 0.1, t0).unwrap();
    let delivered = t0 + rules().lease * 2;
    q.report(&slow, T2, ok(), 20.0, delivered).unwrap();
    drop(rx);
    // The batch is done; the claimant's outcome is checked in a batch of its own.
    let _ = q.submit_checks(vec![(check_task(0), Some(claimant.principal.clone()))]);
    assert!(
        q.orphans(delivered).is_empty(),
        "the slow worker has just delivered: at work, though it last asked two leases ago"
    );
    assert_eq!(
        q.orphans(delivered + rules().lease).len(),
        1,
        "silent for a lease's length after delivering: the coordinator's"
    );
}

/// A quarantined worker loses its leases to the queue and every later call of its is refused, so
/// it can neither report nor hold work.
#[test]
fn a_quarantined_worker_loses_its_leases_and_is_refused() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let liar = outside(&q, "liar", 2, t0).unwrap();
    let honest = outside(&q, "honest", 2, t0).unwrap();
    let rx = q.submit(tasks(1..=2));
    assert_eq!(ids(&q.lease(&liar, 2, t0).unwrap().0), [1, 2]);
    q.quarantine(&claimant(&liar));
    let refused = QueueError::Quarantined(liar.worker);
    assert_eq!(q.report(&liar, T1, ok(), 0.1, t0), Err(refused.clone()));
    assert_eq!(q.lease(&liar, 1, t0).map(|_| ()), Err(refused.clone()));
    assert_eq!(
        q.heartbeat(&liar, &[T1], t0).map(|_| ()),
        Err(refused.clone())
    );
    assert_eq!(q.release(&liar, &[T1]), Err(refused));
    assert_eq!(
        ids(&q.lease(&honest, 2, t0).unwrap().0),
        [1, 2],
        "back in the queue"
    );
    q.report(&honest, T1, ok(), 0.1, t0).unwrap();
    assert_eq!(
        rx.try_recv().unwrap().origin,
        Origin::Claim(claimant(&honest))
    );
    assert!(q.is_quarantined(&claimant(&liar)) && !q.is_quarantined(&claimant(&honest)));
}

/// Registrations are bounded (each holds a few hundred bytes until dropped as silent): at most
/// MAX_WORKERS outside workers are registered at once; the coordinator's own trusted workers are
/// never shut out, and room comes back as silent workers are dropped.
#[test]
fn registrations_are_bounded_and_free_again_when_silent_ones_go() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    for i in 0..MAX_WORKERS {
        outside(&q, &format!("w{i}"), 1, t0).unwrap();
    }
    assert_eq!(
        outside(&q, "one more", 1, t0),
        Err(QueueError::TooManyWorkers)
    );
    assert!(
        q.register("local-0", 1, Principal::Local, true, t0).is_ok(),
        "trusted: never shut out"
    );
    q.reap(t0 + rules().worker_timeout);
    assert!(outside(&q, "after", 1, t0 + rules().worker_timeout).is_ok());
}

#[test]
fn the_server_closes_only_when_every_worker_has_heard_the_run_finished() {
    // A worker between two calls when the run ends must not find the port closed, retry until it
    // gives up and exit with an error: the run stays reachable until it has been told.
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let leaser = outside(&q, "leaser", 1, t0).unwrap();
    let beater = outside(&q, "beater", 1, t0).unwrap();
    let silent = outside(&q, "silent", 1, t0).unwrap();
    assert!(!q.everyone_told(), "the run has not finished");
    q.finish();
    assert!(!q.everyone_told());
    let t1 = t0 + Duration::from_secs(1);
    assert_eq!(q.lease(&leaser, 1, t1).unwrap(), (Vec::new(), true));
    let (revoked, finished) = q.heartbeat(&beater, &[], t1).unwrap();
    assert!(revoked.is_empty() && finished);
    assert!(!q.everyone_told(), "{} has not called since", silent.worker);
    q.reap(t0 + rules().worker_timeout);
    assert!(
        q.everyone_told(),
        "a worker dropped for silence is not waited for"
    );
}
