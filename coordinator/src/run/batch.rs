//! One evaluator call: tasks numbered in the search's order, outcomes a resumed run's store
//! already holds taken from there, every new outcome stored the moment it arrives (or, for a
//! part the search may still drop, held until it keeps it), and outside workers' claims settled
//! (`verification.rs`) before the search sees them.

use std::collections::HashMap;
use std::sync::Mutex;

use amorph::genome::Genome;
use amorph::task::Outcome;
use amorph::voxel::GridDims;

use super::{Result, RunContext};
use crate::evaluator::{Completion, Evaluator, Origin, Task};
use crate::ids::TaskId;
use crate::store::{EvaluationRecord, Purpose, StoreError, StoredEvaluation, unix_now};
use crate::verification::{self, Decisive, EARLIER_SESSION, Evaluated};

/// The run's accounts that every batch reads and advances: the last epoch ended, the evaluations
/// counted, the last task number given, and the outcomes an earlier, interrupted session of the
/// run stored, by task id (see [`crate::store`]), which a batch takes instead of evaluating again.
#[derive(Debug, Default)]
pub(crate) struct Ledger {
    pub(crate) epoch: usize,
    pub(crate) evaluations: u64,
    pub(crate) next_task: u64,
    pub(crate) replay: HashMap<TaskId, StoredEvaluation>,
}

/// One batch of genomes per island, numbered as tasks of the search: the unit a purpose, a
/// resolution and an epoch of the run store belong to.
pub(super) struct Part {
    tasks: Vec<Task>,
    /// Island of each task.
    islands: Vec<u32>,
    /// Tasks per island, to group the outcomes back.
    sizes: Vec<usize>,
    epoch: usize,
    purpose: Purpose,
    resolution: String,
}

impl Part {
    /// Numbers `genomes` as the search's next tasks. Children belong to the epoch they are bred
    /// for, everything else to the epoch just ended.
    pub(super) fn number(
        ledger: &mut Ledger,
        genomes: &[Vec<Genome>],
        dims: GridDims,
        purpose: Purpose,
    ) -> Self {
        let epoch = match purpose {
            Purpose::Child | Purpose::Asked => ledger.epoch + 1,
            Purpose::Initial | Purpose::Reevaluation | Purpose::FinestCheck => ledger.epoch,
        };
        let mut tasks = Vec::new();
        let mut islands = Vec::new();
        for (island, batch) in genomes.iter().enumerate() {
            for genome in batch {
                ledger.next_task += 1;
                tasks.push(Task {
                    id: TaskId(ledger.next_task),
                    genome: genome.clone(),
                    dims,
                });
                islands.push(island as u32);
            }
        }
        Self {
            tasks,
            islands,
            sizes: genomes.iter().map(Vec::len).collect(),
            epoch,
            purpose,
            resolution: dims.to_string(),
        }
    }

    fn record<'a>(
        &'a self,
        slot: usize,
        done: &'a Completion,
        finished_unix: f64,
    ) -> EvaluationRecord<'a> {
        EvaluationRecord {
            task_id: self.tasks[slot].id,
            epoch: self.epoch,
            island: self.islands[slot],
            purpose: self.purpose,
            resolution: self.resolution.clone(),
            genome: &self.tasks[slot].genome,
            outcome: &done.outcome,
            worker: &done.worker,
            wall_seconds: done.wall_seconds,
            finished_unix,
            unchecked: matches!(done.origin, Origin::Claim(_)),
        }
    }

    fn group(&self, evaluated: Vec<Evaluated>) -> Vec<Vec<Evaluated>> {
        let mut evaluated = evaluated.into_iter();
        self.sizes
            .iter()
            .map(|&n| evaluated.by_ref().take(n).collect())
            .collect()
    }
}

/// A part evaluated but not yet in the run store: its new outcomes (when they finished) and the
/// errors workers reported on its tasks. [`Held::keep`] stores them and counts the part's
/// evaluations; dropping it leaves no trace, so the run is as if the part had never been asked.
pub(super) struct Held {
    part: Part,
    fresh: Vec<(usize, Completion, f64)>,
    errors: Vec<(TaskId, String, String)>,
    replayed: usize,
}

impl Held {
    pub(super) fn keep(self, ledger: &mut Ledger, ctx: &RunContext<'_>) -> Result<()> {
        for (slot, done, finished) in &self.fresh {
            ctx.store
                .record_evaluation(&self.part.record(*slot, done, *finished))?;
        }
        for (task, worker, message) in &self.errors {
            ctx.store.record_task_error(*task, worker, message)?;
        }
        for _ in 0..self.fresh.len() + self.replayed {
            ctx.progress.evaluated();
        }
        ledger.evaluations += self.part.tasks.len() as u64;
        Ok(())
    }
}

/// Each part's outcomes, grouped by island.
type PartOutcomes = Vec<Vec<Vec<Evaluated>>>;

/// Evaluates `parts` as one evaluator call, their fresh tasks in part order (so the first part's
/// tasks are handed out first), and returns each part's outcomes grouped by island. The first
/// `stored` parts are stored as their outcomes arrive and counted at once; the rest come back
/// [`Held`], each with its outcomes (replayed ones included) for the search to keep or drop.
/// Outside workers' outcomes are still claims: [`settle`] them before use.
pub(super) fn evaluate_parts(
    ledger: &mut Ledger,
    evaluator: &mut dyn Evaluator,
    parts: Vec<Part>,
    stored: usize,
    ctx: &RunContext<'_>,
) -> Result<(PartOutcomes, Vec<Held>)> {
    let mut evaluated: Vec<Vec<Option<Evaluated>>> =
        parts.iter().map(|p| vec![None; p.tasks.len()]).collect();
    let mut replayed = vec![0; parts.len()];
    let mut fresh = Vec::new();
    // (part, slot) of each fresh task.
    let mut fresh_at = Vec::new();
    for (p, part) in parts.iter().enumerate() {
        for (slot, task) in part.tasks.iter().enumerate() {
            // Taken only where it is this task: children bred beside a finest-level check and
            // dropped by the switch held these task numbers before the re-evaluation that
            // follows took them, and that re-evaluation must still find its stored outcomes.
            let matches = ledger.replay.get(&task.id).is_some_and(|s| {
                s.resolution == part.resolution
                    && serde_json::to_string(&task.genome).is_ok_and(|g| g == s.genome_json)
            });
            let stored_outcome = if matches {
                ledger.replay.remove(&task.id)
            } else {
                None
            };
            match stored_outcome {
                Some(s) => {
                    evaluated[p][slot] = Some(Evaluated {
                        task: task.id,
                        outcome: s.outcome,
                        claimant: s.unchecked.then_some(EARLIER_SESSION),
                    });
                    if p < stored {
                        ctx.progress.evaluated();
                    } else {
                        replayed[p] += 1;
                    }
                }
                None => {
                    fresh.push(task.clone());
                    fresh_at.push((p, slot));
                }
            }
        }
    }

    let mut held_fresh: Vec<Vec<(usize, Completion, f64)>> = vec![Vec::new(); parts.len()];
    let mut held_errors: Vec<Vec<(TaskId, String, String)>> = vec![Vec::new(); parts.len()];
    if !fresh.is_empty() {
        let store_error: Mutex<Option<StoreError>> = Mutex::new(None);
        let holding: Mutex<Vec<(usize, Completion, f64)>> = Mutex::new(Vec::new());
        let on_done = |_: &Task, done: &Completion| {
            let (p, slot) = fresh_at[done.slot];
            if p >= stored {
                let mut held = holding.lock().unwrap_or_else(|e| e.into_inner());
                held.push((done.slot, done.clone(), unix_now()));
                return;
            }
            ctx.progress.evaluated();
            if let Err(e) = ctx
                .store
                .record_evaluation(&parts[p].record(slot, done, unix_now()))
            {
                let mut first = store_error.lock().unwrap_or_else(|e| e.into_inner());
                first.get_or_insert(e);
            }
        };
        let results = evaluator.evaluate(&fresh, &on_done)?;
        if let Some(e) = store_error.into_inner().unwrap_or_else(|e| e.into_inner()) {
            return Err(e.into());
        }
        // In the order they finished, each under its part.
        for (at, done, finished) in holding.into_inner().unwrap_or_else(|e| e.into_inner()) {
            let (p, slot) = fresh_at[at];
            held_fresh[p].push((slot, done, finished));
        }
        for ((p, slot), done) in fresh_at.iter().zip(results) {
            evaluated[*p][*slot] = Some(Evaluated {
                task: parts[*p].tasks[*slot].id,
                outcome: done.outcome,
                claimant: match done.origin {
                    Origin::Claim(claimant) => Some(claimant),
                    Origin::Trusted | Origin::GaveUp => None,
                },
            });
        }
        for (task, worker, message) in evaluator.take_worker_errors() {
            match parts[stored..]
                .iter()
                .position(|part| part.tasks.iter().any(|t| t.id == task))
            {
                Some(p) => held_errors[stored + p].push((task, worker, message)),
                None => ctx.store.record_task_error(task, &worker, &message)?,
            }
        }
    }

    let mut outcomes = Vec::new();
    let mut held = Vec::new();
    for (p, ((part, evaluated), (fresh, errors))) in parts
        .into_iter()
        .zip(evaluated)
        .zip(held_fresh.into_iter().zip(held_errors))
        .enumerate()
    {
        let evaluated = evaluated
            .into_iter()
            .map(|e| e.expect("every task has an outcome"))
            .collect();
        outcomes.push(part.group(evaluated));
        if p < stored {
            ledger.evaluations += part.tasks.len() as u64;
        } else {
            held.push(Held {
                part,
                fresh,
                errors,
                replayed: replayed[p],
            });
        }
    }
    Ok((outcomes, held))
}

/// Evaluates one batch of genomes per island as a single evaluator call, returning the outcomes
/// (with their task ids) grouped the same way. Tasks whose outcome a resumed run's store already
/// holds take it from there; every new outcome is stored the moment it arrives. Outside workers'
/// outcomes are still claims: [`settle`] them before use.
pub(super) fn evaluate_all(
    ledger: &mut Ledger,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    purpose: Purpose,
    ctx: &RunContext<'_>,
) -> Result<Vec<Vec<Evaluated>>> {
    let part = Part::number(ledger, genomes, dims, purpose);
    let (mut outcomes, _) = evaluate_parts(ledger, evaluator, vec![part], 1, ctx)?;
    Ok(outcomes.pop().expect("one part"))
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
pub(crate) fn evaluate_settled(
    ledger: &mut Ledger,
    evaluator: &mut dyn Evaluator,
    genomes: &[Vec<Genome>],
    dims: GridDims,
    purpose: Purpose,
    ctx: &RunContext<'_>,
) -> Result<Vec<Vec<(TaskId, Outcome)>>> {
    let batch = evaluate_all(ledger, evaluator, genomes, dims, purpose, ctx)?;
    settle(
        batch,
        genomes,
        dims,
        evaluator,
        ctx,
        &verification::all_decide,
    )
}
