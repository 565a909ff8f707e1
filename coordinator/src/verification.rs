//! Which outcomes of a batch must be checked before the search may use them, and the loop that
//! checks them.
//!
//! An outside worker's outcome is a claim (`Origin::Claim`). Checking every claim would double the
//! cost of a run; checking none would let one worker with the token steer it. The search is
//! steered only by outcomes that change a population (an initial or re-evaluated individual, a
//! child that replaces its dominant parent, and through those every best and every migrant), so
//! those are checked, each by a second evaluation elsewhere (`Evaluator::check`), before the batch
//! is applied. A correction can change which children win, so the selection repeats until every
//! deciding outcome is settled. A worker caught disagreeing has every other outcome of the batch
//! checked too. Honest workers' claims are confirmed to the bit, so the run is bit-identical with
//! and without verification.

use amorph::genome::Genome;
use amorph::task::Outcome;
use amorph::voxel::GridDims;
use tracing::warn;

use crate::evaluator::{Claim, Claimant, Evaluator, EvaluatorError, Task, Verdict};
use crate::ids::{TaskId, WorkerId};
use crate::principal::Principal;
use crate::store::StoreError;

/// One evaluated task of a batch, as the search receives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluated {
    pub task: TaskId,
    pub outcome: Outcome,
    /// The outside worker whose unchecked word `outcome` is; `None` once checked, or when this
    /// process evaluated it.
    pub claimant: Option<Claimant>,
}

/// For a batch as it stands, which outcomes would change a population, grouped like the batch.
pub type Decisive<'a> = &'a dyn Fn(&[Vec<Evaluated>]) -> Vec<Vec<bool>>;

/// The claimant of an unchecked outcome an earlier session of the run stored: any outside
/// principal may have made it, so this process makes its check.
pub const EARLIER_SESSION: Claimant = Claimant {
    worker: WorkerId { serial: 0, tag: 0 },
    principal: Principal::EarlierSession,
};

#[derive(Debug, thiserror::Error)]
pub enum VerificationError {
    #[error(transparent)]
    Evaluator(#[from] EvaluatorError),
    #[error(transparent)]
    Store(#[from] StoreError),
}

/// Checks the claims of `batch` (grouped like `genomes`, evaluated at `dims`) that `decisive`
/// marks, repeating until none is left unchecked; hands every verdict to `record` (the run store)
/// before the batch takes its outcome. Returns how many checks were made.
pub fn confirm(
    batch: &mut [Vec<Evaluated>],
    genomes: &[Vec<Genome>],
    dims: GridDims,
    evaluator: &mut dyn Evaluator,
    decisive: Decisive<'_>,
    record: &mut dyn FnMut(&Claim, &Verdict) -> Result<(), StoreError>,
) -> Result<u64, VerificationError> {
    let mut checks = 0;
    loop {
        let deciding = decisive(batch);
        let mut at = Vec::new();
        let mut claims = Vec::new();
        for (g, group) in batch.iter().enumerate() {
            for (i, e) in group.iter().enumerate() {
                let Some(claimant) = &e.claimant else {
                    continue;
                };
                if deciding[g][i] || evaluator.doubts_every_claim_of(claimant) {
                    at.push((g, i));
                    claims.push(Claim {
                        task: Task {
                            id: e.task,
                            genome: genomes[g][i].clone(),
                            dims,
                        },
                        outcome: e.outcome.clone(),
                        claimant: claimant.clone(),
                    });
                }
            }
        }
        if claims.is_empty() {
            return Ok(checks);
        }
        let verdicts = evaluator.check(&claims)?;
        checks += claims.len() as u64;
        for ((g, i), (claim, verdict)) in at.into_iter().zip(claims.iter().zip(verdicts)) {
            for liar in &verdict.liars {
                warn!(worker = %liar, task = %claim.task.id, "worker caught disagreeing with a check");
            }
            record(claim, &verdict)?;
            let e = &mut batch[g][i];
            e.outcome = verdict.outcome;
            e.claimant = None;
        }
    }
}

/// Every outcome of the batch decides (initial and re-evaluated populations).
pub fn all_decide(batch: &[Vec<Evaluated>]) -> Vec<Vec<bool>> {
    batch.iter().map(|g| vec![true; g.len()]).collect()
}

#[cfg(test)]
mod tests;
