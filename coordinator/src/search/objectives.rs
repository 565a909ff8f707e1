//! A run with several objectives (`[search] objectives`): each outcome's point in them, and how an
//! island keeps its population by where its members stand among each other's trade-offs: their
//! non-dominated front, then the room around them on it (crowding distance, see [`super::pareto`]).

use std::sync::Arc;

use amorph::task::{Objective, Outcome, Scene};
use amorph::voxel::GridDims;
use serde::{Deserialize, Serialize};

use super::pareto::{crowding_distances, dominates, fronts, hypervolume};
use crate::ids::TaskId;

/// `[search] selection`: how an island of a multi-objective run keeps its population.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// Deterministic crowding, the paper's search with Pareto replacement: a child takes its
    /// dominant parent's slot if it dominates the parent or, where neither dominates, if it would
    /// stand there in a better front, or in the same front with more room.
    Crowding,
    /// NSGA-II (Deb et al. 2002): parents by binary tournament on standing; the population and its
    /// children cut back to the population's size, front by front, the last front by room. The
    /// default: on the beam's RMS error against voxels it reached the larger hypervolume on five
    /// seeds of five (docs/explanation/results.md).
    #[default]
    Nsga2,
}

impl Selection {
    pub fn is_default(&self) -> bool {
        *self == Selection::default()
    }
}

/// The objectives a run trades off, and the resolution its populations are evaluated at.
#[derive(Clone, Debug)]
pub struct Pareto {
    scene: Arc<Scene>,
    /// Indices into the task's objectives, in the config's order.
    chosen: Vec<usize>,
    /// Those objectives, in the same order.
    objectives: Vec<Objective>,
    pub selection: Selection,
    /// The hypervolume's reference point, minimized like the points.
    reference: Vec<f64>,
    /// Where the outcomes being compared were evaluated (the level's resolution).
    pub dims: GridDims,
}

/// A slot's standing: its front (0 is non-dominated) and its crowding distance on that front.
pub type Standing = (usize, f64);

/// Whether standing `a` is better than `b`: a lower front, or the same front and more room.
pub fn stands_better(a: Standing, b: Standing) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 > b.1)
}

impl Pareto {
    /// `names` and `reference` as the config validated them (the task's objectives, a value each).
    pub fn new(
        scene: Arc<Scene>,
        names: &[String],
        selection: Selection,
        reference: &[f64],
        dims: GridDims,
    ) -> Self {
        let objectives = scene.objectives();
        let chosen: Vec<usize> = (names.iter())
            .map(|n| {
                (objectives.iter().position(|o| o.name == n))
                    .expect("the config names the task's objectives")
            })
            .collect();
        let reference = (chosen.iter().zip(reference))
            .map(|(&k, &r)| objectives[k].minimized(r))
            .collect();
        let objectives = chosen.iter().map(|&k| objectives[k]).collect();
        Self {
            scene,
            chosen,
            objectives,
            selection,
            reference,
            dims,
        }
    }

    /// The run's objectives, in the config's order.
    pub fn objectives(&self) -> &[Objective] {
        &self.objectives
    }

    /// An outcome's values as the task states them (`None` for a failure).
    pub fn values(&self, outcome: &Outcome) -> Option<Vec<f64>> {
        let all = self.scene.objective_values(outcome, self.dims)?;
        Some(self.chosen.iter().map(|&k| all[k]).collect())
    }

    /// An outcome's point, every coordinate to be minimized: a value, negated where more is
    /// better. A failure is infinite in every objective, so every evaluated design dominates it.
    pub fn point(&self, outcome: &Outcome) -> Vec<f64> {
        match self.values(outcome) {
            Some(values) => self.minimized(&values),
            None => vec![f64::INFINITY; self.chosen.len()],
        }
    }

    fn minimized(&self, values: &[f64]) -> Vec<f64> {
        (self.objectives.iter().zip(values))
            .map(|(o, &v)| o.minimized(v))
            .collect()
    }

    /// Each outcome's standing among `outcomes`.
    pub fn standings(&self, outcomes: &[&Outcome]) -> Vec<Standing> {
        let points: Vec<Vec<f64>> = outcomes.iter().map(|o| self.point(o)).collect();
        standings(&points)
    }

    /// The crowding rule: whether `newcomer` takes slot `slot` from its occupant among
    /// `occupants` (a child its dominant parent's, a migrant the slot it arrives at).
    pub fn replaces(&self, occupants: &[&Outcome], slot: usize, newcomer: &Outcome) -> bool {
        let points: Vec<Vec<f64>> = occupants.iter().map(|o| self.point(o)).collect();
        replaces(points, slot, self.point(newcomer))
    }

    /// Slots from the best standing to the worst (the lower slot on a tie).
    pub fn ranked(&self, outcomes: &[&Outcome]) -> Vec<usize> {
        ranked(&outcomes.iter().map(|o| self.point(o)).collect::<Vec<_>>())
    }

    /// NSGA-II's cut: the indices of the `size` best-standing of `outcomes`, whole fronts first
    /// and the front that does not fit by room, in ascending order.
    pub fn survivors(&self, outcomes: &[&Outcome], size: usize) -> Vec<usize> {
        survivors(
            &outcomes.iter().map(|o| self.point(o)).collect::<Vec<_>>(),
            size,
        )
    }

    /// The hypervolume `outcomes` dominate up to the reference point (failures add nothing).
    pub fn hypervolume(&self, outcomes: &[&Outcome]) -> f64 {
        let points: Vec<Vec<f64>> = outcomes.iter().map(|o| self.point(o)).collect();
        let refs: Vec<&[f64]> = points.iter().map(Vec::as_slice).collect();
        hypervolume(&refs, &self.reference)
    }
}

/// The crowding rule on minimized points: whether `newcomer` takes slot `slot` of `points`. It
/// does if it dominates the occupant, never if the occupant dominates it, and otherwise if it
/// would stand better there than the occupant does.
pub fn replaces(mut points: Vec<Vec<f64>>, slot: usize, newcomer: Vec<f64>) -> bool {
    if dominates(&newcomer, &points[slot]) {
        return true;
    }
    if dominates(&points[slot], &newcomer) {
        return false;
    }
    let before = standings(&points)[slot];
    points[slot] = newcomer;
    stands_better(standings(&points)[slot], before)
}

/// Indices of minimized `points` from the best standing to the worst (the lower index on a tie).
pub fn ranked(points: &[Vec<f64>]) -> Vec<usize> {
    let standings = standings(points);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        (standings[a].0.cmp(&standings[b].0))
            .then(standings[b].1.total_cmp(&standings[a].1))
            .then(a.cmp(&b))
    });
    order
}

/// NSGA-II's cut on minimized points: the `size` best-standing indices, in ascending order.
pub fn survivors(points: &[Vec<f64>], size: usize) -> Vec<usize> {
    let mut kept = ranked(points);
    kept.truncate(size);
    kept.sort_unstable();
    kept
}

/// A run's non-dominated designs: its objectives, and each design's evaluation and values.
#[derive(Clone, Debug, PartialEq)]
pub struct Front {
    pub objectives: Vec<Objective>,
    /// Ascending by task id; values in the objectives' order and the task's units.
    pub members: Vec<(TaskId, Vec<f64>)>,
    /// The hypervolume the members dominate up to the config's reference point.
    pub hypervolume: f64,
    /// The objectives' values of the run's fittest design by the task's single fitness, for
    /// comparison (`None` if it failed).
    pub fittest: Option<Vec<f64>>,
}

impl Front {
    /// The members along the first objective (then by evaluation), as pareto.csv, pareto.png
    /// and the report show them.
    pub fn along_first(&self) -> Vec<&(TaskId, Vec<f64>)> {
        let mut rows: Vec<&(TaskId, Vec<f64>)> = self.members.iter().collect();
        rows.sort_by(|a, b| a.1[0].total_cmp(&b.1[0]).then(a.0.cmp(&b.0)));
        rows
    }
}

impl Pareto {
    /// The non-dominated designs among `evaluations` (all evaluated at this resolution): a
    /// design whose values equal an earlier evaluation's counts once, as the earlier.
    pub fn front<'a>(&self, evaluations: impl IntoIterator<Item = (TaskId, &'a Outcome)>) -> Front {
        let mut evaluated: Vec<(TaskId, &Outcome)> = evaluations.into_iter().collect();
        evaluated.sort_by_key(|(task, _)| *task);
        // In task order, an archive of the non-dominated so far: a newcomer equal to or dominated
        // by a member is dropped, and drops the members it dominates.
        let mut archive: Vec<(TaskId, Vec<f64>, Vec<f64>)> = Vec::new();
        for (task, outcome) in evaluated {
            let Some(values) = self.values(outcome) else {
                continue;
            };
            let point = self.minimized(&values);
            if (archive.iter()).any(|(_, _, p)| *p == point || dominates(p, &point)) {
                continue;
            }
            archive.retain(|(_, _, p)| !dominates(&point, p));
            archive.push((task, values, point));
        }
        let points: Vec<&[f64]> = archive.iter().map(|(_, _, p)| p.as_slice()).collect();
        Front {
            objectives: self.objectives.clone(),
            hypervolume: hypervolume(&points, &self.reference),
            members: archive
                .into_iter()
                .map(|(task, values, _)| (task, values))
                .collect(),
            fittest: None,
        }
    }
}

/// Each point's front and crowding distance on it.
fn standings(points: &[Vec<f64>]) -> Vec<Standing> {
    let refs: Vec<&[f64]> = points.iter().map(Vec::as_slice).collect();
    let mut standing = vec![(0, 0.0); points.len()];
    for (rank, front) in fronts(&refs).into_iter().enumerate() {
        let members: Vec<&[f64]> = front.iter().map(|&i| refs[i]).collect();
        for (&i, distance) in front.iter().zip(crowding_distances(&members)) {
            standing[i] = (rank, distance);
        }
    }
    standing
}

#[cfg(test)]
mod tests;
