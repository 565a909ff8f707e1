//! The queue's rules for principals: one credential is one voice however many workers it
//! registers, it holds no more than its share while others wait, it cannot keep work by naming
//! it in heartbeats, and a lie quarantines the credential that told it and nobody else.

use super::tests::{check_task, claimant, ids, ok, outside, rules, tasks};
use super::*;
use std::time::Duration;

const T1: TaskId = TaskId(1);

fn under(q: &TaskQueue, name: &str, principal: &str, capacity: u32, now: Instant) -> Caller {
    q.register(
        name,
        capacity,
        Principal::Credential(principal.into()),
        false,
        now,
    )
    .unwrap()
}

/// Three registrations of one credential give one error between them: the task is not failed,
/// and none of them is leased it again; a worker of another credential evaluates it.
#[test]
fn one_credential_is_one_voice_however_many_workers_it_registers() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let sybils: Vec<Caller> = (0..3)
        .map(|i| under(&q, &format!("s{i}"), "mallory", 1, t0))
        .collect();
    let rx = q.submit(tasks(1..=1));
    assert_eq!(ids(&q.lease(&sybils[0], 1, t0).unwrap().0), [1]);
    q.report(&sybils[0], T1, Err("no".into()), 0.0, t0).unwrap();
    for s in &sybils[1..] {
        assert!(
            q.lease(s, 1, t0).unwrap().0.is_empty(),
            "its credential failed it"
        );
    }
    assert!(rx.try_recv().is_err(), "not failed by one voice");
    let honest = outside(&q, "honest", 1, t0).unwrap();
    assert_eq!(ids(&q.lease(&honest, 1, t0).unwrap().0), [1]);
    q.report(&honest, T1, ok(), 0.0, t0).unwrap();
    assert_eq!(rx.try_recv().unwrap().outcome, ok().unwrap());
}

/// A check of a claim goes to no registration of the claimant's credential; under the shared
/// token, to no shared-token worker; and when only the claimant's credential is at work, to the
/// coordinator.
#[test]
fn a_check_goes_to_another_credential_or_to_the_coordinator() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let a1 = under(&q, "a1", "alice", 2, t0);
    let a2 = under(&q, "a2", "alice", 2, t0);
    let s1 = q.register("s1", 2, Principal::Shared, false, t0).unwrap();
    let s2 = q.register("s2", 2, Principal::Shared, false, t0).unwrap();
    let _ = q.submit_checks(vec![
        (check_task(0), Some(a1.principal.clone())),
        (check_task(1), Some(Principal::Shared)),
    ]);
    assert!(
        q.lease(&a2, 2, t0)
            .unwrap()
            .0
            .iter()
            .all(|t| t.id == check_task(1).id)
    );
    assert!(
        q.lease(&s2, 2, t0)
            .unwrap()
            .0
            .iter()
            .all(|t| t.id == check_task(0).id)
    );
    assert!(q.lease(&a1, 2, t0).unwrap().0.is_empty() && q.lease(&s1, 2, t0).unwrap().0.is_empty());

    let q = TaskQueue::new(rules());
    let s1 = q.register("s1", 2, Principal::Shared, false, t0).unwrap();
    let _ = q.submit_checks(vec![(check_task(0), Some(Principal::Shared))]);
    assert!(q.lease(&s1, 2, t0).unwrap().0.is_empty());
    assert_eq!(
        q.orphans(t0).len(),
        1,
        "only the claimant's principal is at work"
    );
    let local = q.register("local", 1, Principal::Local, true, t0).unwrap();
    assert_eq!(
        ids(&q.lease(&local, 1, t0).unwrap().0),
        [check_task(0).id.0]
    );
}

/// A worker that declares capacity 1,024 beside an honest worker waiting for one task leaves it
/// that task; with nobody else waiting it takes up to its capacity, itself capped.
#[test]
fn a_worker_takes_no_more_than_its_share_while_another_principal_waits() {
    let q = TaskQueue::new(QueueRules {
        max_capacity: 16,
        ..rules()
    });
    let t0 = Instant::now();
    let hoarder = under(&q, "hoarder", "mallory", 1024, t0);
    let honest = outside(&q, "honest", 2, t0).unwrap();
    // The honest worker asked before there was work: it waits for two.
    assert!(q.lease(&honest, 2, t0).unwrap().0.is_empty());
    let _rx = q.submit(tasks(1..=20));
    let taken = q.lease(&hoarder, 1024, t0).unwrap().0;
    assert_eq!(
        taken.len(),
        16,
        "capped at max_capacity, and 18 left for a share of 2"
    );
    assert_eq!(ids(&q.lease(&honest, 2, t0).unwrap().0), [17, 18]);

    let q = TaskQueue::new(rules());
    let hoarder = under(&q, "hoarder", "mallory", 1024, t0);
    let honest = outside(&q, "honest", 2, t0).unwrap();
    assert!(q.lease(&honest, 2, t0).unwrap().0.is_empty());
    let _rx = q.submit(tasks(1..=6));
    assert_eq!(q.lease(&hoarder, 1024, t0).unwrap().0.len(), 4);
    assert_eq!(
        q.lease(&honest, 2, t0).unwrap().0.len(),
        2,
        "its share was kept"
    );
    // Nobody waits any more once the honest worker's call is older than the waiting window.
    let _rx = q.submit(tasks(7..=12));
    let later = t0 + Duration::from_secs(10);
    assert_eq!(q.lease(&hoarder, 1024, later).unwrap().0.len(), 6);
}

/// A worker that names its leases in every heartbeat and never reports keeps them only while no
/// other principal waits for work: a waiting worker takes over a task held past twice the median
/// evaluation time, and every lease lapses at its lifetime, which follows measured evaluation
/// times. What lapsed goes to another principal first.
#[test]
fn a_hoarded_task_is_taken_over_by_a_waiting_worker_and_lapses_at_its_lifetime() {
    let q = TaskQueue::new(QueueRules {
        lease: Duration::from_secs(2),
        heartbeat_interval: Duration::from_millis(100),
        max_lease: Duration::from_secs(3600),
        ..rules()
    });
    let t0 = Instant::now();
    let honest = outside(&q, "honest", 1, t0).unwrap();
    // Eight honest evaluations of 100 ms each: backups after 200 ms, a lifetime of
    // 8 × 100 ms raised to the 2 s lease.
    let _rx = q.submit(tasks(1..=8));
    let mut now = t0;
    for id in 1..=8 {
        assert_eq!(ids(&q.lease(&honest, 1, now).unwrap().0), [id]);
        now += Duration::from_millis(100);
        q.report(&honest, TaskId(id), ok(), 0.1, now).unwrap();
    }
    let hoarder = under(&q, "hoarder", "mallory", 4, now);
    let _rx = q.submit(tasks(9..=12));
    assert_eq!(q.lease(&hoarder, 4, now).unwrap().0.len(), 4);
    let held = [TaskId(9), TaskId(10), TaskId(11), TaskId(12)];
    assert!(
        q.lease(&honest, 1, now + Duration::from_millis(150))
            .unwrap()
            .0
            .is_empty()
    );
    now += Duration::from_millis(250);
    assert_eq!(
        ids(&q.lease(&honest, 1, now).unwrap().0),
        [9],
        "held past the backup time: taken over"
    );
    assert_eq!(q.heartbeat(&hoarder, &held, now).unwrap().0, [TaskId(9)]);
    // The hoarder keeps naming the rest; at 2 s they lapse all the same.
    now += Duration::from_millis(1800);
    q.heartbeat(&hoarder, &held, now).unwrap();
    q.reap(now);
    assert_eq!(
        q.stats().queued,
        3,
        "the lifetime is over: back in the queue"
    );

    // What a principal handed back waits for another principal that waits for work.
    let q = TaskQueue::new(rules());
    let mallory = under(&q, "m", "mallory", 2, t0);
    let carol = outside(&q, "carol", 1, t0).unwrap();
    let _rx = q.submit(tasks(1..=2));
    assert_eq!(q.lease(&mallory, 2, t0).unwrap().0.len(), 2);
    assert!(q.lease(&carol, 1, t0).unwrap().0.is_empty(), "carol waits");
    assert_eq!(q.release(&mallory, &[T1, TaskId(2)]), Ok(2));
    assert!(
        q.lease(&mallory, 2, t0).unwrap().0.is_empty(),
        "handed back: carol's first"
    );
    assert_eq!(ids(&q.lease(&carol, 1, t0).unwrap().0), [1]);
    assert_eq!(
        ids(&q.lease(&mallory, 2, t0).unwrap().0),
        [2],
        "with nobody else waiting, it may take it again"
    );
}

/// Registrations are bounded per credential: over the bound, the credential's longest-idle
/// registration makes room, and when all are at work the call is refused; another credential
/// is not touched either way.
#[test]
fn registrations_are_bounded_per_credential_and_idle_ones_make_room() {
    let q = TaskQueue::new(QueueRules {
        max_workers_per_credential: 3,
        ..rules()
    });
    let t0 = Instant::now();
    let honest = outside(&q, "honest", 1, t0).unwrap();
    let flood: Vec<Caller> = (0..3)
        .map(|i| under(&q, &format!("f{i}"), "mallory", 1, t0))
        .collect();
    let t1 = t0 + Duration::from_secs(10);
    under(&q, "f3", "mallory", 1, t1);
    assert_eq!(q.stats().evicted, 1);
    assert_eq!(
        q.heartbeat(&flood[0], &[], t1).unwrap_err(),
        QueueError::UnknownWorker(flood[0].worker),
        "the longest idle made room"
    );
    assert!(
        q.heartbeat(&honest, &[], t1).is_ok(),
        "another credential is untouched"
    );
    // All three at work (waiting for work): the fourth is refused.
    let q = TaskQueue::new(QueueRules {
        max_workers_per_credential: 3,
        ..rules()
    });
    let busy: Vec<Caller> = (0..3)
        .map(|i| under(&q, &format!("b{i}"), "mallory", 1, t0))
        .collect();
    for b in &busy {
        q.lease(b, 1, t0).unwrap();
    }
    assert!(matches!(
        q.register("b3", 1, Principal::Credential("mallory".into()), false, t0),
        Err(QueueError::TooManyForCredential { limit: 3, .. })
    ));
    assert!(outside(&q, "other", 1, t0).is_ok());
}

/// A lie quarantines its credential, every registration of it and any later one; under the
/// shared token, only the registration that lied.
#[test]
fn a_lie_quarantines_its_credential_and_under_the_shared_token_only_the_liar() {
    let q = TaskQueue::new(rules());
    let t0 = Instant::now();
    let m1 = under(&q, "m1", "mallory", 1, t0);
    let m2 = under(&q, "m2", "mallory", 1, t0);
    let honest = outside(&q, "honest", 1, t0).unwrap();
    q.quarantine(&claimant(&m1));
    assert_eq!(
        q.lease(&m2, 1, t0).unwrap_err(),
        QueueError::Quarantined(m2.worker)
    );
    assert!(matches!(
        q.register("m3", 1, Principal::Credential("mallory".into()), false, t0),
        Err(QueueError::Quarantined(_))
    ));
    assert!(q.lease(&honest, 1, t0).is_ok());

    let s1 = q.register("s1", 1, Principal::Shared, false, t0).unwrap();
    let s2 = q.register("s2", 1, Principal::Shared, false, t0).unwrap();
    q.quarantine(&claimant(&s1));
    assert_eq!(
        q.lease(&s1, 1, t0).unwrap_err(),
        QueueError::Quarantined(s1.worker)
    );
    assert!(
        q.lease(&s2, 1, t0).is_ok(),
        "an honest holder of the shared token works on"
    );
    assert!(q.register("s3", 1, Principal::Shared, false, t0).is_ok());
}
