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
use crate::evaluator::{
    Claim, Claimant, Completion, Evaluator, EvaluatorError, LocalEvaluator, Origin, Task, Verdict,
};
use crate::ids::TaskId;

#[derive(Debug)]
pub struct ClusterEvaluator {
    queue: Arc<TaskQueue>,
    shutdown: Arc<AtomicBool>,
    /// The run's scene, for the tie-break when a check disagrees with a claim.
    scene: Arc<Scene>,
    /// This process's cores, for the tasks no worker at work may take (`TaskQueue::orphans`).
    here: LocalEvaluator,
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
            here: LocalEvaluator::new(scene.clone(), 0),
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

    /// Waits for one completion per task of the batch just submitted on `done`; tasks no worker
    /// at work may take (`TaskQueue::orphans`) are evaluated here meanwhile.
    fn collect(
        &mut self,
        tasks: &[Task],
        done: &std::sync::mpsc::Receiver<Completion>,
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        let mut completions: Vec<Option<Completion>> = vec![None; tasks.len()];
        let mut remaining = tasks.len();
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
                    let orphans: Vec<Task> = (self.queue.orphans(Instant::now()).iter())
                        .map(|t| Task::clone(t))
                        .collect();
                    self.stats.by_coordinator += orphans.len() as u64;
                    for done in self.here.evaluate(&orphans, &|_, _| {})? {
                        let id = orphans[done.slot].id;
                        self.queue.finish_here(id, done.outcome, done.wall_seconds);
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

    /// The coordinator's own evaluation of a claim both of whose witnesses are unproven: whoever
    /// differs from it is quarantined.
    fn settle(&mut self, claim: &Claim, check: &Completion) -> (Outcome, Vec<Claimant>) {
        self.stats.by_coordinator += 1;
        let truth = self.scene.evaluate(&claim.task.genome, claim.task.dims);
        let truth_text = outcome_text(&truth);
        let mut liars = Vec::new();
        if outcome_text(&claim.outcome) != truth_text {
            liars.push(claim.claimant.clone());
        }
        if let Origin::Claim(w) = &check.origin
            && outcome_text(&check.outcome) != truth_text
        {
            liars.push(w.clone());
        }
        (truth, liars)
    }

    fn punish(&self, liar: &Claimant, task: TaskId) {
        warn!(worker = %liar.worker, principal = %liar.principal, %task, "outcome disagrees with the one that holds: quarantined");
        self.queue.quarantine(liar);
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

    /// Each claim is evaluated again by a principal that may check its claimant's. Agreement to
    /// the bit confirms it. On disagreement: a trusted checker's outcome holds; a checker caught
    /// lying meanwhile is ignored and the claim checked again; a claimant already caught lying is
    /// replaced by the checker, whose outcome then needs a check of its own; otherwise the
    /// coordinator evaluates it, and whoever differs is quarantined. So the coordinator's own
    /// re-evaluations stop at the first proven lie of each liar: one that contradicts a hundred
    /// honest claims costs one evaluation here and a hundred checks elsewhere.
    fn check(&mut self, claims: &[Claim]) -> Result<Vec<Verdict>, EvaluatorError> {
        let n = claims.len();
        let mut standing: Vec<Claim> = claims.to_vec();
        let mut verdicts: Vec<Option<Verdict>> = vec![None; n];
        let mut liars: Vec<Vec<Claimant>> = vec![Vec::new(); n];
        let mut checkers: Vec<Vec<String>> = vec![Vec::new(); n];
        loop {
            let pending: Vec<usize> = (0..n).filter(|&i| verdicts[i].is_none()).collect();
            if pending.is_empty() {
                break;
            }
            let tasks: Vec<Task> = pending
                .iter()
                .map(|&i| {
                    let id = TaskId(self.next_check);
                    self.next_check += 1;
                    Task {
                        id,
                        genome: standing[i].task.genome.clone(),
                        dims: standing[i].task.dims,
                    }
                })
                .collect();
            let done = self.queue.submit_checks(
                tasks
                    .iter()
                    .zip(&pending)
                    .map(|(t, &i)| (t.clone(), Some(standing[i].claimant.principal.clone())))
                    .collect(),
            );
            let checks = self.collect(&tasks, &done, &|_, _| {})?;
            self.stats.checks += pending.len() as u64;
            for (&i, check) in pending.iter().zip(&checks) {
                let claim = standing[i].clone();
                if let Origin::Claim(checker) = &check.origin
                    && self.queue.is_quarantined(checker)
                {
                    continue; // caught lying on another task meanwhile: its word counts for nothing
                }
                checkers[i].push(check.worker.clone());
                let agrees = check.origin != Origin::GaveUp
                    && outcome_text(&claim.outcome) == outcome_text(&check.outcome);
                if agrees {
                    verdicts[i] = Some(Verdict {
                        outcome: claim.outcome,
                        agreed: liars[i].is_empty(),
                        checker: checkers[i].join(", then "),
                        liars: std::mem::take(&mut liars[i]),
                    });
                    continue;
                }
                self.stats.disagreements += 1;
                let (truth, caught) = match &check.origin {
                    Origin::Trusted => (check.outcome.clone(), vec![claim.claimant.clone()]),
                    Origin::Claim(checker) if self.queue.is_quarantined(&claim.claimant) => {
                        standing[i] = Claim {
                            outcome: check.outcome.clone(),
                            claimant: checker.clone(),
                            ..claim
                        };
                        continue;
                    }
                    Origin::Claim(_) | Origin::GaveUp => {
                        let settled = self.settle(&claim, check);
                        checkers[i].push("coordinator".into());
                        settled
                    }
                };
                for liar in &caught {
                    self.punish(liar, claim.task.id);
                }
                liars[i].extend(caught);
                verdicts[i] = Some(Verdict {
                    outcome: truth,
                    agreed: false,
                    checker: checkers[i].join(", then "),
                    liars: std::mem::take(&mut liars[i]),
                });
            }
        }
        let verdicts: Vec<Verdict> = verdicts.into_iter().map(|v| v.expect("settled")).collect();
        info!(
            checks = n,
            disagreed = verdicts.iter().filter(|v| !v.agreed).count(),
            "claims checked"
        );
        Ok(verdicts)
    }

    fn doubts_every_claim_of(&self, claimant: &Claimant) -> bool {
        self.check_all || self.queue.is_quarantined(claimant)
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
