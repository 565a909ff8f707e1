//! What a run reports about itself: why it stopped, its history rows, and the final summary with
//! the fittest individual. Shared by the run loop, the results folder and the progress line.

use amorph::voxel::GridDims;
use serde::Serialize;

use crate::search::{Front, Individual};

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    EvaluationBudget,
    WallTime,
    TargetReached,
    Shutdown,
}

/// One line of the fitness history: an island after an epoch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HistoryRow {
    pub epoch: usize,
    pub evaluations: u64,
    pub wall_seconds: f64,
    pub resolution: String,
    pub island: u32,
    pub best_fitness: Option<f64>,
    /// The task's figure of the island's best (e.g. the beam's RMS error, %).
    pub best_figure: Option<f64>,
    pub mean_fitness: Option<f64>,
    pub replacements: usize,
    /// In a multi-objective run: the hypervolume the island's population dominates.
    pub hypervolume: Option<f64>,
}

/// What a finished run hands back (and writes to its results folder).
#[derive(Debug)]
pub struct RunSummary {
    pub stop: StopReason,
    pub epochs: usize,
    pub evaluations: u64,
    /// Children not evaluated because they made their dominant parent's design
    /// (`search.skip_unchanged`; 0 without it).
    pub unchanged_children: u64,
    pub wall_seconds: f64,
    pub dims: GridDims,
    /// Every island's final population, in slot order.
    pub populations: Vec<Vec<Individual>>,
    pub history: Vec<HistoryRow>,
    /// In a multi-objective run: its non-dominated designs at the final resolution.
    pub pareto: Option<Front>,
}

impl RunSummary {
    /// The fittest individual of the run (the lowest island, then slot, on a tie).
    pub fn best(&self) -> &Individual {
        fittest(self.populations.iter().flatten())
    }
}

/// The fittest of `individuals`: the first on a tie, so the lowest island and slot win. Panics on
/// none: every population holds at least two individuals (the config's rule).
pub fn fittest<'a>(individuals: impl IntoIterator<Item = &'a Individual>) -> &'a Individual {
    let mut individuals = individuals.into_iter();
    let first = individuals.next().expect("a population is never empty");
    individuals.fold(first, |best, ind| {
        if ind.outcome.is_fitter_than(&best.outcome) {
            ind
        } else {
            best
        }
    })
}
