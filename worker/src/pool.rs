//! The CPU pool: evaluations run on plain threads of their own, never on the async runtime, so a
//! long simulation cannot stall heartbeats or the network. One evaluation per thread at a time,
//! each on that thread alone or shared with a `rayon` pool of its own (same bits either way).

use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use amorph::dynamics::EvaluationThreads;
use amorph::genome::Genome;
use amorph::outcome::Failure;
use amorph::task::Outcome;
use amorph::task::Scene;
use amorph::voxel::GridDims;
use amorph_proto::ids::TaskId;
use tokio::sync::mpsc::UnboundedSender;

/// What the pool computes for a task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EvaluationMode {
    /// Voxelize and simulate: the real evaluation.
    Physics,
    /// Answer at once with an empty-design outcome: for measuring the coordinator's dispatch
    /// capacity without any physics in the way.
    Instant,
}

/// One task for the pool.
#[derive(Debug)]
pub struct Job {
    pub task_id: TaskId,
    pub genome: Genome,
    pub scene: Arc<Scene>,
    pub dims: GridDims,
}

/// A finished job: the outcome and the evaluation's wall time, s.
#[derive(Debug)]
pub struct JobDone {
    pub task_id: TaskId,
    pub outcome: Outcome,
    pub wall_seconds: f64,
}

/// `threads` evaluation threads fed from one queue. Dropping the pool lets each thread finish its
/// current job and exit.
#[derive(Debug)]
pub struct Pool {
    jobs: Sender<Job>,
    threads: usize,
}

impl Pool {
    /// Starts `threads` threads, each sharing its evaluations with `per_evaluation` threads of
    /// its own (1: evaluating alone); fails (instead of panicking) when the system will not give
    /// them.
    pub fn new(
        threads: usize,
        per_evaluation: usize,
        mode: EvaluationMode,
        done: UnboundedSender<JobDone>,
    ) -> std::io::Result<Self> {
        let (jobs, queue) = channel::<Job>();
        let queue = Arc::new(Mutex::new(queue));
        for i in 0..threads {
            let queue = queue.clone();
            let done = done.clone();
            let shared =
                EvaluationThreads::new(per_evaluation, move |j| format!("evaluate-{i}.{j}"))
                    .map_err(std::io::Error::other)?;
            std::thread::Builder::new()
                .name(format!("evaluate-{i}"))
                .spawn(move || work(&queue, &shared, mode, &done))?;
        }
        Ok(Self { jobs, threads })
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    pub fn submit(&self, job: Job) {
        // The threads only stop once this pool is dropped, so the queue is always open here.
        let _ = self.jobs.send(job);
    }
}

fn work(
    queue: &Mutex<Receiver<Job>>,
    shared: &EvaluationThreads,
    mode: EvaluationMode,
    done: &UnboundedSender<JobDone>,
) {
    loop {
        let job = {
            let queue = queue.lock().unwrap_or_else(|e| e.into_inner());
            match queue.recv() {
                Ok(job) => job,
                Err(_) => return,
            }
        };
        let started = Instant::now();
        let outcome = match mode {
            EvaluationMode::Physics => shared.run(|| job.scene.evaluate(&job.genome, job.dims)),
            EvaluationMode::Instant => Outcome::failed(Failure::Empty),
        };
        let finished = JobDone {
            task_id: job.task_id,
            outcome,
            wall_seconds: started.elapsed().as_secs_f64(),
        };
        if done.send(finished).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests;
