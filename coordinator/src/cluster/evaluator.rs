//! The search's view of the cluster: an [`Evaluator`] that puts a batch on the task queue and
//! waits for its completions, whoever delivers them and in whatever order.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use amorph::task::Outcome;

use super::queue::TaskQueue;
use crate::evaluator::{Completion, Evaluator, EvaluatorError, Task};
use crate::ids::TaskId;

#[derive(Debug)]
pub struct ClusterEvaluator {
    queue: Arc<TaskQueue>,
    shutdown: Arc<AtomicBool>,
}

impl ClusterEvaluator {
    pub fn new(queue: Arc<TaskQueue>, shutdown: Arc<AtomicBool>) -> Self {
        Self { queue, shutdown }
    }
}

impl Evaluator for ClusterEvaluator {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Outcome>, EvaluatorError> {
        let done = self.queue.submit(tasks.to_vec());
        let mut outcomes: Vec<Option<Outcome>> = vec![None; tasks.len()];
        let mut remaining = tasks.len();
        while remaining > 0 {
            match done.recv_timeout(Duration::from_millis(100)) {
                Ok(completion) => {
                    on_done(&tasks[completion.slot], &completion);
                    if outcomes[completion.slot]
                        .replace(completion.outcome)
                        .is_none()
                    {
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
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(EvaluatorError::Stopped("the task queue closed".into()));
                }
            }
        }
        Ok(outcomes.into_iter().map(|o| o.expect("counted")).collect())
    }

    fn status(&self) -> Option<String> {
        let s = self.queue.stats();
        Some(format!(
            "{} workers, {} leased, {} queued",
            s.workers, s.leased, s.queued
        ))
    }

    fn take_worker_errors(&mut self) -> Vec<(TaskId, String, String)> {
        self.queue
            .take_noted_errors()
            .into_iter()
            .map(|(t, w, m)| (t, w.to_string(), m))
            .collect()
    }
}
