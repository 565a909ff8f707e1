//! One batch of evaluations: tasks numbered in the search's order, outcomes a resumed run's store
//! already holds taken from there, every new outcome stored the moment it arrives, and outside
//! workers' claims settled (`verification.rs`) before the search sees them.

use std::sync::Mutex;

use amorph::genome::Genome;
use amorph::task::Outcome;
use amorph::voxel::GridDims;

use super::search::Search;
use super::{Result, RunContext};
use crate::evaluator::{Completion, Evaluator, Origin, Task};
use crate::ids::TaskId;
use crate::store::{EvaluationRecord, Purpose, StoreError};
use crate::verification::{self, Decisive, EARLIER_SESSION, Evaluated};

/// Evaluates one batch of genomes per island as a single evaluator call, returning the outcomes
/// (with their task ids) grouped the same way. Tasks whose outcome a resumed run's store already
/// holds take it from there; every new outcome is stored the moment it arrives. Outside workers'
/// outcomes are still claims: [`settle`] them before use.
pub(super) fn evaluate_all(
    search: &mut Search,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    purpose: Purpose,
    ctx: &RunContext<'_>,
) -> Result<Vec<Vec<Evaluated>>> {
    let epoch = match purpose {
        Purpose::Child => search.epoch + 1,
        Purpose::Initial | Purpose::Reevaluation | Purpose::FinestCheck => search.epoch,
    };
    let resolution = dims.to_string();
    let mut tasks = Vec::new();
    let mut islands = Vec::new();
    for (island, batch) in genomes.iter().enumerate() {
        for genome in batch {
            search.next_task += 1;
            tasks.push(Task {
                id: TaskId(search.next_task),
                genome: genome.clone(),
                dims,
            });
            islands.push(island as u32);
        }
    }

    let mut evaluated: Vec<Option<Evaluated>> = vec![None; tasks.len()];
    let mut fresh = Vec::new();
    let mut fresh_slots = Vec::new();
    for (slot, task) in tasks.iter().enumerate() {
        let stored = search.replay.remove(&task.id).filter(|s| {
            s.resolution == resolution
                && serde_json::to_string(&task.genome).is_ok_and(|g| g == s.genome_json)
        });
        match stored {
            Some(s) => {
                evaluated[slot] = Some(Evaluated {
                    task: task.id,
                    outcome: s.outcome,
                    claimant: s.unchecked.then_some(EARLIER_SESSION),
                });
                ctx.progress.evaluated();
            }
            None => {
                fresh.push(task.clone());
                fresh_slots.push(slot);
            }
        }
    }

    if !fresh.is_empty() {
        let store_error: Mutex<Option<StoreError>> = Mutex::new(None);
        let on_done = |task: &Task, done: &Completion| {
            ctx.progress.evaluated();
            let record = EvaluationRecord {
                task_id: task.id,
                epoch,
                island: islands[fresh_slots[done.slot]],
                purpose,
                resolution: resolution.clone(),
                genome: &task.genome,
                outcome: &done.outcome,
                worker: &done.worker,
                wall_seconds: done.wall_seconds,
                unchecked: matches!(done.origin, Origin::Claim(_)),
            };
            if let Err(e) = ctx.store.record_evaluation(&record) {
                let mut first = store_error.lock().unwrap_or_else(|e| e.into_inner());
                first.get_or_insert(e);
            }
        };
        let results = evaluator.evaluate(&fresh, &on_done)?;
        if let Some(e) = store_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e.into());
        }
        for (slot, done) in fresh_slots.iter().zip(results) {
            evaluated[*slot] = Some(Evaluated {
                task: tasks[*slot].id,
                outcome: done.outcome,
                claimant: match done.origin {
                    Origin::Claim(w) => Some(w),
                    Origin::Trusted | Origin::GaveUp => None,
                },
            });
        }
        for (task, worker, message) in evaluator.take_worker_errors() {
            ctx.store.record_task_error(task, &worker, &message)?;
        }
    }
    search.evaluations += tasks.len() as u64;

    let mut evaluated = evaluated
        .into_iter()
        .map(|e| e.expect("every task has an outcome"));
    Ok(genomes
        .iter()
        .map(|g| evaluated.by_ref().take(g.len()).collect())
        .collect())
}

/// The outcomes of a batch once every outside worker's claim that `decisive` marks is checked
/// (`verification.rs`), each check recorded in the run store.
pub(super) fn settle(
    mut batch: Vec<Vec<Evaluated>>,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    evaluator: &mut dyn Evaluator,
    ctx: &RunContext<'_>,
    decisive: Decisive<'_>,
) -> Result<Vec<Vec<(TaskId, Outcome)>>> {
    verification::confirm(
        &mut batch,
        genomes,
        dims,
        evaluator,
        decisive,
        &mut |claim, verdict| {
            ctx.store.record_check(
                claim.task.id,
                &claim.claimant.to_string(),
                &claim.outcome,
                verdict,
            )
        },
    )?;
    Ok(batch
        .into_iter()
        .map(|g| g.into_iter().map(|e| (e.task, e.outcome)).collect())
        .collect())
}

/// [`evaluate_all`] then [`settle`] with every claim decisive: a batch whose every outcome the
/// search keeps (initial populations, re-evaluations, checks at the finest level).
pub(super) fn evaluate_settled(
    search: &mut Search,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    purpose: Purpose,
    ctx: &RunContext<'_>,
) -> Result<Vec<Vec<(TaskId, Outcome)>>> {
    let batch = evaluate_all(search, evaluator, genomes, dims, purpose, ctx)?;
    settle(
        batch,
        genomes,
        dims,
        evaluator,
        ctx,
        &verification::all_decide,
    )
}
