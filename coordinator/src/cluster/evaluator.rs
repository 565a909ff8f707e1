//! The search's view of the cluster: an [`Evaluator`] that puts a batch on the task queue and
//! waits for its completions, whoever delivers them and in whatever order, and that checks an
//! outside worker's claim by a second evaluation elsewhere (verification in the style of volunteer
//! computing: a worker holding the token can report anything, so its word alone never decides).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use amorph::task::{Outcome, Scene};
use tracing::{info, warn};

use super::queue::TaskQueue;
use crate::evaluator::{Claim, Completion, Evaluator, EvaluatorError, Origin, Task, Verdict};
use crate::ids::{TaskId, WorkerId};

#[derive(Debug)]
pub struct ClusterEvaluator {
    queue: Arc<TaskQueue>,
    shutdown: Arc<AtomicBool>,
    /// The run's scene, for the evaluations the coordinator makes itself: a check no other
    /// worker may take, and the tie-break when a check disagrees with a claim.
    scene: Arc<Scene>,
    next_check: u64,
    /// Added to the search's task ids on the queue. The queue needs ids that increase from batch
    /// to batch (a late result for an earlier batch must never pass for one of the current
    /// batch), while the search hands out ids again when it drops children it sent out ahead
    /// of their epoch (`resolution.overlap_finest_checks`); from then on the queue's ids run
    /// this far ahead of the search's. Zero in a run that never dropped any.
    queue_offset: u64,
    /// The first and last queue ids of the batch last submitted ((0, 0) before the first: the
    /// search's ids start at 1).
    queued: (u64, u64),
    stats: CheckStats,
    /// `cluster.verify = "all"`: check every outside claim, deciding or not.
    check_all: bool,
}

/// What verification has cost and found so far in this process.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CheckStats {
    /// Second evaluations of claims.
    pub checks: u64,
    /// Of those, made by the coordinator itself because no other worker could.
    pub by_coordinator: u64,
    /// Checks that disagreed with their claim, each settled by the coordinator's own evaluation
    /// unless a trusted worker had made the check.
    pub disagreements: u64,
}

impl ClusterEvaluator {
    pub fn new(queue: Arc<TaskQueue>, shutdown: Arc<AtomicBool>, scene: Arc<Scene>) -> Self {
        Self {
            queue,
            shutdown,
            scene,
            next_check: TaskId::FIRST_CHECK,
            queue_offset: 0,
            queued: (0, 0),
            stats: CheckStats::default(),
            check_all: false,
        }
    }

    /// Checks every outside worker's outcome, not only those that would change a population.
    pub fn checking_every_claim(mut self, all: bool) -> Self {
        self.check_all = all;
        self
    }

    pub fn check_stats(&self) -> CheckStats {
        self.stats
    }

    /// Waits for one completion per task of the batch just submitted on `done`; in a batch of
    /// checks, those no worker at work may take are evaluated here (a search batch has none, so
    /// its wait does not scan the queue).
    fn collect(
        &mut self,
        tasks: &[Task],
        done: &std::sync::mpsc::Receiver<Completion>,
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        let mut completions: Vec<Option<Completion>> = vec![None; tasks.len()];
        let mut remaining = tasks.len();
        let checks = tasks.first().is_some_and(|t| t.id.is_check());
        while remaining > 0 {
            match done.recv_timeout(Duration::from_millis(100)) {
                Ok(completion) => {
                    on_done(&tasks[completion.slot], &completion);
                    let slot = completion.slot;
                    if completions[slot].replace(completion).is_none() {
                        remaining -= 1;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if self.shutdown.load(Ordering::Relaxed) {
                        return Err(EvaluatorError::Stopped(format!(
                            "shut down with {} of {} tasks of the batch outstanding (finished ones are in the run store)",
                            remaining,
                            tasks.len()
                        )));
                    }
                    let orphans = if checks {
                        self.queue.orphan_checks(Instant::now())
                    } else {
                        Vec::new()
                    };
                    for task in orphans {
                        let started = Instant::now();
                        let outcome = self.scene.evaluate(&task.genome, task.dims);
                        self.stats.by_coordinator += 1;
                        self.queue
                            .finish_here(task.id, outcome, started.elapsed().as_secs_f64());
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(EvaluatorError::Stopped("the task queue closed".into()));
                }
            }
        }
        Ok(completions
            .into_iter()
            .map(|c| c.expect("counted"))
            .collect())
    }

    /// The outcome that holds when a check disagrees with a claim: a trusted checker's, else the
    /// coordinator's own evaluation. Everyone whose outcome differs from it is quarantined.
    fn settle(&mut self, claim: &Claim, check: &Completion) -> Verdict {
        self.stats.disagreements += 1;
        let (truth, checker) = match check.origin {
            Origin::Trusted => (check.outcome.clone(), check.worker.clone()),
            Origin::Claim(_) | Origin::GaveUp => {
                self.stats.by_coordinator += 1;
                let truth = self.scene.evaluate(&claim.task.genome, claim.task.dims);
                (truth, format!("{}, then coordinator", check.worker))
            }
        };
        let truth_text = outcome_text(&truth);
        let mut liars = Vec::new();
        if outcome_text(&claim.outcome) != truth_text {
            liars.push(claim.claimant);
        }
        if let Origin::Claim(w) = check.origin
            && outcome_text(&check.outcome) != truth_text
        {
            liars.push(w);
        }
        for &liar in &liars {
            warn!(worker = %liar, task = %claim.task.id, "worker's outcome disagrees with the coordinator's own evaluation: quarantined");
            self.queue.quarantine(liar);
        }
        Verdict {
            outcome: truth,
            agreed: false,
            checker,
            liars,
        }
    }
}

/// Outcomes compared to the bit: their JSON, which writes every float in its shortest exact form
/// (so -0.0 and 0.0 differ, as their bits do).
fn outcome_text(outcome: &Outcome) -> String {
    serde_json::to_string(outcome).expect("outcomes serialize")
}

impl Evaluator for ClusterEvaluator {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        let (Some(first), Some(last)) = (tasks.first(), tasks.last()) else {
            return Ok(Vec::new());
        };
        if first.id.0 + self.queue_offset <= self.queued.1 {
            self.queue_offset = self.queued.1 + 1 - first.id.0;
        }
        self.queued = (
            first.id.0 + self.queue_offset,
            last.id.0 + self.queue_offset,
        );
        let queued: Vec<Task> = (tasks.iter())
            .map(|t| Task {
                id: TaskId(t.id.0 + self.queue_offset),
                ..t.clone()
            })
            .collect();
        let done = self.queue.submit(queued);
        self.collect(tasks, &done, on_done)
    }

    fn check(&mut self, claims: &[Claim]) -> Result<Vec<Verdict>, EvaluatorError> {
        let tasks: Vec<Task> = claims
            .iter()
            .map(|c| {
                let id = TaskId(self.next_check);
                self.next_check += 1;
                Task {
                    id,
                    genome: c.task.genome.clone(),
                    dims: c.task.dims,
                }
            })
            .collect();
        let done = self.queue.submit_excluding(
            tasks
                .iter()
                .zip(claims)
                .map(|(t, c)| (t.clone(), Some(c.claimant)))
                .collect(),
        );
        let checks = self.collect(&tasks, &done, &|_, _| {})?;
        self.stats.checks += claims.len() as u64;
        let verdicts: Vec<Verdict> = claims
            .iter()
            .zip(&checks)
            .map(|(claim, check)| {
                if check.origin != Origin::GaveUp
                    && outcome_text(&claim.outcome) == outcome_text(&check.outcome)
                {
                    Verdict::agreed(claim.outcome.clone(), check.worker.clone())
                } else {
                    self.settle(claim, check)
                }
            })
            .collect();
        info!(
            checks = claims.len(),
            disagreed = verdicts.iter().filter(|v| !v.agreed).count(),
            "claims checked"
        );
        Ok(verdicts)
    }

    fn doubts_every_claim_of(&self, worker: WorkerId) -> bool {
        self.check_all || self.queue.is_quarantined(worker)
    }

    fn status(&self) -> Option<String> {
        let s = self.queue.stats();
        Some(format!(
            "{} workers, {} leased, {} queued, {} checks",
            s.workers, s.leased, s.queued, self.stats.checks
        ))
    }

    fn take_worker_errors(&mut self) -> Vec<(TaskId, String, String)> {
        self.queue
            .take_noted_errors()
            .into_iter()
            .map(|(t, w, m)| {
                let task = if (self.queued.0..=self.queued.1).contains(&t.0) {
                    TaskId(t.0 - self.queue_offset)
                } else {
                    t
                };
                (task, w.to_string(), m)
            })
            .collect()
    }
}
