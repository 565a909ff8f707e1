//! The evaluator interface between the search and whoever evaluates genomes: local threads here,
//! gRPC workers in the cluster. An evaluation is a pure function of (genome, scene, resolution),
//! so any evaluator gives the search the same outcomes.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use amorph::genome::Genome;
use amorph::outcome::{Failure, Outcome};
use amorph::scene::Scene;
use amorph::voxel::GridDims;

use crate::ids::TaskId;

/// One genome to evaluate at one resolution of the run's scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub id: TaskId,
    pub genome: Genome,
    pub dims: GridDims,
}

#[derive(Debug, thiserror::Error)]
pub enum EvaluatorError {
    #[error("evaluator stopped: {0}")]
    Stopped(String),
}

/// Evaluates a batch of tasks and returns their outcomes in task order. `on_done` is called once
/// per finished task (from any thread), for progress reporting.
pub trait Evaluator {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Outcome) + Sync),
    ) -> Result<Vec<Outcome>, EvaluatorError>;
}

/// Evaluates one task, turning a panic in the physics (a bug of ours) into a failed outcome so
/// one bad design never brings a run down.
pub fn evaluate_task(scene: &Scene, task: &Task) -> Outcome {
    catch_unwind(AssertUnwindSafe(|| {
        amorph::evaluate::evaluate(&task.genome, scene, task.dims)
    }))
    .unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Outcome::failed(Failure::Internal(message))
    })
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
        on_done: &(dyn Fn(&Outcome) + Sync),
    ) -> Result<Vec<Outcome>, EvaluatorError> {
        let next = AtomicUsize::new(0);
        let scene = &*self.scene;
        let mut done: Vec<(usize, Outcome)> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..self.threads.min(tasks.len()))
                .map(|_| {
                    s.spawn(|| {
                        let mut mine = Vec::new();
                        loop {
                            let i = next.fetch_add(1, Ordering::Relaxed);
                            let Some(task) = tasks.get(i) else { break };
                            let outcome = evaluate_task(scene, task);
                            on_done(&outcome);
                            mine.push((i, outcome));
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
        done.sort_by_key(|&(i, _)| i);
        Ok(done.into_iter().map(|(_, o)| o).collect())
    }
}
