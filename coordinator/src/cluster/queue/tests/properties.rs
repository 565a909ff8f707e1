//! Property tests: random interleavings of register / lease / heartbeat / report / release /
//! expiry / silence / quarantine from several workers under several principals (some with more
//! than one registration), honest or not, with forged ids and stolen sessions, with the queue's
//! invariants checked after every step, and at the end every task finished exactly once with the
//! first accepted outcome.

use std::collections::HashMap;

use proptest::prelude::*;

use super::tests::{claimant, rules, tasks};
use super::*;
use amorph::outcome::Failure;
use std::time::Duration;

const TASKS: u64 = 6;

#[derive(Clone, Debug)]
enum Op {
    Register {
        capacity: u32,
        /// 0 to 2: credentials p0 to p2; 3: the shared token.
        principal: u8,
    },
    Lease {
        worker: usize,
        max: u32,
    },
    Heartbeat {
        worker: usize,
        tasks: u8,
    },
    Report {
        worker: usize,
        task: u64,
        error: bool,
    },
    Release {
        worker: usize,
        tasks: u8,
    },
    /// Time passes and the reaper runs: leases lapse, workers that did not call go silent.
    Advance {
        ms: u64,
    },
    /// A made-up worker id, of this process or another.
    Forged {
        serial: u64,
        task: u64,
    },
    /// A worker is caught disagreeing with a check.
    Quarantine {
        worker: usize,
    },
    /// A real worker id with another worker's session secret, or under another credential.
    Stolen {
        worker: usize,
        thief: usize,
    },
}

fn principal(i: u8) -> Principal {
    match i {
        3 => Principal::Shared,
        i => Principal::Credential(format!("p{i}").into()),
    }
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        1 => (1u32..4, 0u8..4).prop_map(|(capacity, principal)| Op::Register { capacity, principal }),
        4 => (0usize..8, 0u32..5).prop_map(|(worker, max)| Op::Lease { worker, max }),
        2 => (0usize..8, any::<u8>()).prop_map(|(worker, tasks)| Op::Heartbeat { worker, tasks }),
        5 => (0usize..8, 0u64..TASKS + 2, prop::bool::weighted(0.4))
            .prop_map(|(worker, task, error)| Op::Report { worker, task, error }),
        1 => (0usize..8, any::<u8>()).prop_map(|(worker, tasks)| Op::Release { worker, tasks }),
        2 => (0u64..12_000).prop_map(|ms| Op::Advance { ms }),
        1 => (0u64..12, 0u64..TASKS + 2).prop_map(|(serial, task)| Op::Forged { serial, task }),
        1 => (0usize..8).prop_map(|worker| Op::Quarantine { worker }),
        1 => (0usize..8, 0usize..8).prop_map(|(worker, thief)| Op::Stolen { worker, thief }),
    ]
}

fn named(mask: u8) -> Vec<TaskId> {
    (1..=TASKS)
        .filter(|i| mask & (1 << i) != 0)
        .map(TaskId)
        .collect()
}

/// What the test saw: the first accepted outcome of each task and every completion.
#[derive(Default)]
struct Seen {
    accepted: HashMap<TaskId, Outcome>,
    completed: HashMap<usize, Outcome>,
    reports: u64,
}

impl Seen {
    fn drain(&mut self, rx: &Receiver<Completion>) -> Result<(), TestCaseError> {
        while let Ok(c) = rx.try_recv() {
            let task = TaskId(c.slot as u64 + 1);
            prop_assert!(
                self.completed.insert(c.slot, c.outcome.clone()).is_none(),
                "{task} completed twice"
            );
            match self.accepted.get(&task) {
                Some(first) => {
                    prop_assert_eq!(first, &c.outcome, "{} lost its first outcome", task)
                }
                None => prop_assert!(
                    c.worker == "coordinator",
                    "{task} completed with an outcome nobody had accepted"
                ),
            }
        }
        Ok(())
    }

    fn report(
        &mut self,
        q: &TaskQueue,
        worker: &Caller,
        task: TaskId,
        error: bool,
        now: Instant,
    ) -> Result<(), TestCaseError> {
        self.reports += 1;
        let outcome = Outcome::failed(Failure::Internal(format!("report {}", self.reports)));
        let result = if error {
            Err(format!("error {}", self.reports))
        } else {
            Ok(outcome.clone())
        };
        let finished_before = self
            .completed
            .contains_key(&(task.0 as usize).wrapping_sub(1));
        let d = q.report(worker, task, result, 0.0, now);
        if let Ok(Disposition::Accepted) = d {
            prop_assert!(!finished_before, "{task} accepted after it finished");
            prop_assert!(
                self.accepted.insert(task, outcome).is_none(),
                "{task} accepted twice"
            );
        }
        if finished_before {
            prop_assert!(
                !matches!(d, Ok(Disposition::Accepted | Disposition::ErrorNoted)),
                "{task} finished, yet a report changed it: {d:?}"
            );
        }
        Ok(())
    }
}

fn run(ops: Vec<Op>, max_attempts: u32) -> Result<(), TestCaseError> {
    let q = TaskQueue::new(QueueRules {
        max_attempts,
        ..rules()
    });
    let mut now = Instant::now();
    let rx = q.submit(tasks(1..=TASKS));
    let mut workers: Vec<Caller> = Vec::new();
    let mut seen = Seen::default();
    let pick = |workers: &[Caller], i: usize| workers.get(i % workers.len().max(1)).cloned();
    for op in ops {
        match op {
            Op::Register {
                capacity,
                principal: p,
            } => {
                if let Ok(w) = q.register("w", capacity, principal(p), false, now) {
                    workers.push(w);
                }
            }
            Op::Lease { worker, max } => {
                if let Some(w) = pick(&workers, worker)
                    && let Ok((leased, _)) = q.lease(&w, max, now)
                {
                    for t in leased {
                        let i = (t.id.0 - 1) as usize;
                        prop_assert!(
                            !seen.completed.contains_key(&i),
                            "{} leased after it finished",
                            t.id
                        );
                    }
                }
            }
            Op::Heartbeat { worker, tasks } => {
                if let Some(w) = pick(&workers, worker) {
                    let _ = q.heartbeat(&w, &named(tasks), now);
                }
            }
            Op::Report {
                worker,
                task,
                error,
            } => {
                if let Some(w) = pick(&workers, worker) {
                    seen.report(&q, &w, TaskId(task), error, now)?;
                }
            }
            Op::Release { worker, tasks } => {
                if let Some(w) = pick(&workers, worker) {
                    let _ = q.release(&w, &named(tasks));
                }
            }
            Op::Advance { ms } => {
                now += Duration::from_millis(ms);
                q.reap(now);
            }
            Op::Forged { serial, task } => {
                let tag = if serial % 2 == 0 {
                    q.tag
                } else {
                    q.tag ^ 0x5a5a
                };
                let forged = Caller {
                    worker: WorkerId {
                        serial: serial + 100,
                        tag,
                    },
                    principal: principal((serial % 4) as u8),
                    session: "00".repeat(32),
                };
                prop_assert!(
                    q.report(
                        &forged,
                        TaskId(task),
                        Ok(Outcome::failed(Failure::Empty)),
                        0.0,
                        now
                    )
                    .is_err()
                );
                prop_assert!(q.lease(&forged, 4, now).is_err());
            }
            Op::Quarantine { worker } => {
                if let Some(w) = pick(&workers, worker) {
                    q.quarantine(&claimant(&w));
                    let refused = Some(QueueError::Quarantined(w.worker));
                    prop_assert_eq!(q.lease(&w, 4, now).err(), refused.clone());
                    prop_assert_eq!(
                        q.report(&w, TaskId(1), Ok(Outcome::failed(Failure::Empty)), 0.0, now)
                            .err(),
                        refused
                    );
                }
            }
            Op::Stolen { worker, thief } => {
                if let (Some(w), Some(t)) = (pick(&workers, worker), pick(&workers, thief))
                    && w.worker != t.worker
                {
                    for stolen in [
                        Caller {
                            session: t.session.clone(),
                            ..w.clone()
                        },
                        Caller {
                            principal: t.principal.clone(),
                            ..w.clone()
                        },
                    ] {
                        if stolen == w {
                            continue; // same principal: the second case is the worker itself
                        }
                        let refused = Some(QueueError::BadSession(w.worker));
                        prop_assert_eq!(q.lease(&stolen, 4, now).err(), refused.clone());
                        prop_assert_eq!(q.heartbeat(&stolen, &[], now).err(), refused.clone());
                        prop_assert_eq!(q.release(&stolen, &named(0xff)).err(), refused.clone());
                        let report = q.report(
                            &stolen,
                            TaskId(1),
                            Ok(Outcome::failed(Failure::Empty)),
                            0.0,
                            now,
                        );
                        prop_assert_eq!(report.err(), refused);
                    }
                }
            }
        }
        q.lock().check(max_attempts).map_err(TestCaseError::fail)?;
        seen.drain(&rx)?;
    }

    // Honest workers arrive after everyone else has gone: nothing may be stranded.
    now += Duration::from_secs(3600);
    q.reap(now);
    let honest: Vec<Caller> = (0..2)
        .map(|_| super::tests::outside(&q, "honest", 4, now).unwrap())
        .collect();
    for _ in 0..TASKS {
        for w in &honest {
            let (leased, _) = q.lease(w, 4, now).expect("registered");
            for t in leased {
                seen.report(&q, w, t.id, false, now)?;
            }
        }
        q.lock().check(max_attempts).map_err(TestCaseError::fail)?;
    }
    seen.drain(&rx)?;
    prop_assert_eq!(
        seen.completed.len() as u64,
        TASKS,
        "every task finished exactly once"
    );
    prop_assert_eq!(q.stats().queued + q.stats().leased, 0);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn every_task_ends_once_with_its_first_accepted_outcome(
        ops in prop::collection::vec(op(), 0..80),
        max_attempts in 1u32..4,
    ) {
        run(ops, max_attempts)?;
    }
}
