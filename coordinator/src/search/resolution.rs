//! Multi-resolution bootstrapping (paper §III): evaluate at a coarse resolution first and move to
//! the next finer one when progress stalls, or at the latest after a set number of evaluations
//! (a coarse level that keeps improving slowly would otherwise spend the budget on a design the
//! fine grid scores far worse).

use amorph::voxel::GridDims;

use super::stall::Stall;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResolutionSchedule {
    /// Resolutions from coarse to fine, as [nx, ny, nz].
    pub levels: Vec<[usize; 3]>,
    /// Epochs without enough improvement of the run's best fitness before moving to the next level.
    #[serde(default = "default_stall_epochs")]
    pub stall_epochs: usize,
    /// Improvement that counts as progress, relative to the best fitness's magnitude.
    #[serde(default = "default_min_improvement")]
    pub min_improvement: f64,
    /// For each level but the last, the run's evaluations by which it gives way to the next one,
    /// stalled or not. Empty (the default): only the stall rule.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub latest_switch: Vec<u64>,
    /// At a coarse level, the run's best design is also evaluated at the finest level whenever it
    /// changes (one evaluation each), and the stall rule watches the best of those scores instead
    /// of the coarse fitness: a coarse level gives way once it stops finding designs that are
    /// better on the fine grid. Default false (the coarse fitness, the paper's rule). A coarse
    /// level's climbed best can score far worse on the fine grid.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stall_on_finest: bool,
}

fn default_stall_epochs() -> usize {
    10
}
fn default_min_improvement() -> f64 {
    0.02
}

impl ResolutionSchedule {
    pub fn single(dims: GridDims) -> Self {
        Self {
            levels: vec![[dims.nx, dims.ny, dims.nz]],
            stall_epochs: default_stall_epochs(),
            min_improvement: default_min_improvement(),
            latest_switch: Vec::new(),
            stall_on_finest: false,
        }
    }

    pub fn dims(&self, level: usize) -> GridDims {
        let [nx, ny, nz] = self.levels[level];
        GridDims::new(nx, ny, nz)
    }

    /// The finest resolution, the last level.
    pub fn finest(&self) -> GridDims {
        self.dims(self.levels.len() - 1)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.levels.is_empty() {
            return Err("resolution.levels must list at least one resolution".into());
        }
        for (i, l) in self.levels.iter().enumerate() {
            amorph_proto::grid::checked_grid(l.map(|n| n as u64))
                .map_err(|e| format!("resolution.levels[{i}] = {l:?}: {e}"))?;
        }
        if !(self.min_improvement.is_finite() && self.min_improvement >= 0.0) {
            return Err("resolution.min_improvement must be a non-negative number".into());
        }
        let l = &self.latest_switch;
        if !l.is_empty() && l.len() + 1 != self.levels.len() {
            return Err(format!(
                "resolution.latest_switch lists {} evaluation counts: it needs one per level but the last ({})",
                l.len(),
                self.levels.len() - 1
            ));
        }
        if let Some(i) = (1..l.len()).find(|&i| l[i] <= l[i - 1]) {
            return Err(format!(
                "resolution.latest_switch[{i}] = {} must be larger than the one before it ({})",
                l[i],
                l[i - 1]
            ));
        }
        Ok(())
    }
}

/// Tracks stalls and decides when to switch level. A pure function of the best-fitness sequence,
/// so the switch happens at the same epoch in every run with the same seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResolutionState {
    pub level: usize,
    stall: Stall,
}

impl ResolutionState {
    pub fn new() -> Self {
        Self {
            level: 0,
            stall: Stall::new(),
        }
    }

    /// Records the best fitness after an epoch that brought the run to `evaluations`; returns true
    /// when the run should move to the next level (and then resets the stall tracking for it).
    pub fn observe(&mut self, best: f64, evaluations: u64, schedule: &ResolutionSchedule) -> bool {
        let stalled = self.stall.observe(best, schedule.min_improvement);
        let overdue = schedule
            .latest_switch
            .get(self.level)
            .is_some_and(|&latest| evaluations >= latest);
        if self.level + 1 < schedule.levels.len() && (stalled >= schedule.stall_epochs || overdue) {
            self.level += 1;
            self.stall = Stall::new();
            return true;
        }
        false
    }

    /// Whether the run is at its finest resolution.
    pub fn is_final(&self, schedule: &ResolutionSchedule) -> bool {
        self.level + 1 == schedule.levels.len()
    }
}

impl Default for ResolutionState {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests;
