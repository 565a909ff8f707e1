//! The evaluator interface between the search and whoever evaluates genomes: local threads here,
//! gRPC workers in the cluster. An evaluation is a pure function of (genome, scene, resolution),
//! so any evaluator gives the search the same outcomes.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;

use crate::ids::{TaskId, WorkerId};
use crate::principal::Principal;

/// One genome to evaluate at one resolution of the run's scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub id: TaskId,
    pub genome: Genome,
    pub dims: GridDims,
}

/// One finished task of a batch.
#[derive(Clone, Debug, PartialEq)]
pub struct Completion {
    /// Position of the task in its batch.
    pub slot: usize,
    pub outcome: Outcome,
    /// Who evaluated it: a worker's `name (id)`, `local`, or `coordinator` for a task marked
    /// failed after worker errors.
    pub worker: String,
    /// Wall time of the evaluation where it ran, s.
    pub wall_seconds: f64,
    /// Whose word the outcome is.
    pub origin: Origin,
}

/// Whose word an outcome is, which decides whether it must be checked before it may change a
/// population.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Evaluated in this process (its threads, its own local workers, or the coordinator).
    Trusted,
    /// Reported by an outside worker: a claim until a second principal's evaluation agrees.
    Claim(Claimant),
    /// No evaluation: `max_attempts` different workers gave errors, so the task failed.
    GaveUp,
}

/// The outside worker whose word an outcome is, and the principal (credential) behind it.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Claimant {
    pub worker: WorkerId,
    pub principal: Principal,
}

impl std::fmt::Display for Claimant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.principal {
            Principal::EarlierSession => f.write_str("earlier session"),
            ref p => write!(f, "{} ({p})", self.worker),
        }
    }
}

/// An outside worker's outcome for a task, to be evaluated again by another principal.
#[derive(Clone, Debug, PartialEq)]
pub struct Claim {
    pub task: Task,
    pub outcome: Outcome,
    pub claimant: Claimant,
}

/// What a check found: the outcome that holds and who was caught disagreeing with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub outcome: Outcome,
    /// Whether the second evaluation agreed with the claim to the bit.
    pub agreed: bool,
    /// Who made the second evaluation (and the third, when a tie had to be broken).
    pub checker: String,
    /// Workers whose outcome for this task differs from the one that holds; now quarantined.
    pub liars: Vec<Claimant>,
}

impl Verdict {
    /// A check that agreed with its claim: the claim holds and nobody lied.
    pub fn agreed(outcome: Outcome, checker: String) -> Self {
        Self {
            outcome,
            agreed: true,
            checker,
            liars: Vec::new(),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum EvaluatorError {
    #[error("evaluator stopped: {0}")]
    Stopped(String),
}

/// Evaluates a batch of tasks and returns their completions in task order. `on_done` is called
/// once per finished task as it finishes (from the calling thread or any other), so the run store
/// can record it at once.
pub trait Evaluator {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError>;

    /// Evaluates each claim again by someone other than its claimant and returns, in order, the
    /// outcome that holds. An evaluator whose completions are all [`Origin::Trusted`] is never
    /// asked; by default it answers with the claims themselves.
    fn check(&mut self, claims: &[Claim]) -> Result<Vec<Verdict>, EvaluatorError> {
        Ok(claims
            .iter()
            .map(|c| Verdict::agreed(c.outcome.clone(), "none".into()))
            .collect())
    }

    /// Whether every outcome `worker` claims is checked, not only those that would change a
    /// population: it was caught disagreeing with a check, or the run checks every claim
    /// (`cluster.verify = "all"`).
    fn doubts_every_claim_of(&self, _claimant: &Claimant) -> bool {
        false
    }

    /// A one-line state of the evaluator for progress lines (workers, leases), if it has one.
    fn status(&self) -> Option<String> {
        None
    }

    /// Errors workers reported since the last call (task, worker, message), for the run store.
    fn take_worker_errors(&mut self) -> Vec<(TaskId, String, String)> {
        Vec::new()
    }
}

/// Evaluates on threads of this process, one evaluation per thread at a time.
#[derive(Debug)]
pub struct LocalEvaluator {
    scene: Arc<Scene>,
    threads: usize,
}

impl LocalEvaluator {
    /// `threads = 0` uses one thread per available core.
    pub fn new(scene: Arc<Scene>, threads: usize) -> Self {
        let threads = if threads == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            threads
        };
        Self { scene, threads }
    }

    pub fn threads(&self) -> usize {
        self.threads
    }
}

impl Evaluator for LocalEvaluator {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        let next = AtomicUsize::new(0);
        let scene = &*self.scene;
        let mut done: Vec<Completion> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..self.threads.min(tasks.len()))
                .map(|_| {
                    s.spawn(|| {
                        let mut mine = Vec::new();
                        loop {
                            let i = next.fetch_add(1, Ordering::Relaxed);
                            let Some(task) = tasks.get(i) else { break };
                            let started = std::time::Instant::now();
                            let completion = Completion {
                                slot: i,
                                outcome: scene.evaluate(&task.genome, task.dims),
                                worker: "local".into(),
                                wall_seconds: started.elapsed().as_secs_f64(),
                                origin: Origin::Trusted,
                            };
                            on_done(task, &completion);
                            mine.push(completion);
                        }
                        mine
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().expect("evaluation threads catch panics"))
                .collect()
        });
        done.sort_by_key(|c| c.slot);
        Ok(done)
    }
}
