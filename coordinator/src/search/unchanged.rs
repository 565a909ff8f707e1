//! Children that cannot replace their dominant parent are not evaluated
//! (`search.skip_unchanged`).
//!
//! An evaluation is a pure function of the design a genome makes at the level's resolution, and
//! crowding replaces a parent only with a strictly fitter child. A child whose design is its
//! dominant parent's scores the parent's very bits, so it never replaces anything, never counts as
//! an improving nudge and never meets a target its parent has not met: evaluating it buys nothing.
//! Near a good design most nudges move a point by less than a voxel, and a converged island breeds
//! copies of its members, so such children are common where a run spends most of its budget.
//! Dropping them leaves the search exactly as it was, epoch by epoch, on fewer evaluations.

use std::collections::HashMap;

use amorph::task::Scene;
use amorph::voxel::{GridDims, VoxelGrid};

use super::island::{Child, Island};
use crate::ids::TaskId;

/// The designs of the parents checked so far at one resolution, by the task that scored them (a
/// task id names one genome, wherever migration has taken it).
#[derive(Debug, Default)]
pub struct ParentDesigns {
    dims: Option<GridDims>,
    designs: HashMap<TaskId, VoxelGrid>,
}

impl ParentDesigns {
    /// For every child of `children` (grouped as `islands`, each naming a slot of its island as
    /// its dominant parent), whether its design at `dims` is that parent's design. The children's
    /// designs are made on every core: the workers wait for this batch meanwhile.
    pub fn unchanged(
        &mut self,
        islands: &[Island],
        children: &[Vec<Child>],
        scene: &Scene,
        dims: GridDims,
    ) -> Vec<Vec<bool>> {
        if self.dims != Some(dims) {
            self.dims = Some(dims);
            self.designs.clear();
        }
        // Parents no island holds any more are forgotten, so the cache stays one population big.
        let held: std::collections::HashSet<TaskId> = islands
            .iter()
            .flat_map(|i| i.population.iter().map(|ind| ind.task))
            .collect();
        self.designs.retain(|task, _| held.contains(task));
        for (island, children) in islands.iter().zip(children) {
            for child in children {
                let parent = &island.population[child.dominant_parent];
                self.designs
                    .entry(parent.task)
                    .or_insert_with(|| scene.design(&parent.genome, dims));
            }
        }
        let flat: Vec<&Child> = children.iter().flatten().collect();
        let designs = designs_in_parallel(&flat, scene, dims);
        let mut designs = designs.into_iter();
        islands
            .iter()
            .zip(children)
            .map(|(island, children)| {
                children
                    .iter()
                    .map(|child| {
                        let parent = island.population[child.dominant_parent].task;
                        let design = designs.next().expect("one design per child");
                        self.designs[&parent] == design
                    })
                    .collect()
            })
            .collect()
    }
}

/// The designs of `children` at `dims`, in order, made on up to every available core.
fn designs_in_parallel(children: &[&Child], scene: &Scene, dims: GridDims) -> Vec<VoxelGrid> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = children.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let handles: Vec<_> = children
            .chunks(chunk)
            .map(|part| {
                s.spawn(move || {
                    part.iter()
                        .map(|c| scene.design(&c.genome, dims))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("voxelizing a genome does not panic"))
            .collect()
    })
}

/// Keeps at most `left` of the children `keep` marks, taking them in turn from each island (its
/// first, then every island's second, ...), so a budget that ends inside an epoch is spread over
/// the islands. The order is fixed, so the children an epoch evaluated are the first `n` in it
/// whatever budget cut them: a replay needs only the count the run store recorded.
pub fn first_in_turn(keep: &mut [Vec<bool>], left: u64) {
    let mut taken = 0u64;
    let longest = keep.iter().map(Vec::len).max().unwrap_or(0);
    for k in 0..longest {
        for island in keep.iter_mut() {
            if let Some(flag) = island.get_mut(k).filter(|flag| **flag) {
                if taken < left {
                    taken += 1;
                } else {
                    *flag = false;
                }
            }
        }
    }
}

/// Marks the first child in turn (see [`first_in_turn`]) when `keep` marks none: an epoch that
/// evaluated nothing would spend no budget, and a population that only breeds copies of itself
/// would then never end its run.
pub fn keep_at_least_one(keep: &mut [Vec<bool>]) {
    if keep.iter().flatten().any(|&k| k) {
        return;
    }
    if let Some(first) = keep.iter_mut().find_map(|island| island.first_mut()) {
        *first = true;
    }
}

#[cfg(test)]
mod tests;
