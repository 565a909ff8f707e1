//! Multi-resolution bootstrapping (paper §III): evaluate at a coarse resolution first and move to
//! the next finer one when progress stalls.

use amorph::voxel::GridDims;
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
        }
    }

    pub fn dims(&self, level: usize) -> GridDims {
        let [nx, ny, nz] = self.levels[level];
        GridDims::new(nx, ny, nz)
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
        Ok(())
    }
}

/// Tracks stalls and decides when to switch level. A pure function of the best-fitness sequence,
/// so the switch happens at the same epoch in every run with the same seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResolutionState {
    pub level: usize,
    best_at_last_progress: f64,
    epochs_without_progress: usize,
}

impl ResolutionState {
    pub fn new() -> Self {
        Self {
            level: 0,
            best_at_last_progress: f64::NEG_INFINITY,
            epochs_without_progress: 0,
        }
    }

    /// Records the best fitness after an epoch; returns true when the run should move to the next
    /// level (and then resets the stall tracking for it).
    pub fn observe(&mut self, best: f64, schedule: &ResolutionSchedule) -> bool {
        let threshold = self.best_at_last_progress
            + schedule.min_improvement * self.best_at_last_progress.abs();
        if best > threshold || !self.best_at_last_progress.is_finite() {
            self.best_at_last_progress = best;
            self.epochs_without_progress = 0;
        } else {
            self.epochs_without_progress += 1;
        }
        if self.level + 1 < schedule.levels.len()
            && self.epochs_without_progress >= schedule.stall_epochs
        {
            self.level += 1;
            self.best_at_last_progress = f64::NEG_INFINITY;
            self.epochs_without_progress = 0;
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
mod tests {
    use super::*;

    #[test]
    fn switches_after_the_configured_stall() {
        let schedule = ResolutionSchedule {
            levels: vec![[1, 2, 1], [2, 4, 2]],
            stall_epochs: 3,
            min_improvement: 0.1,
        };
        let mut s = ResolutionState::new();
        assert!(!s.observe(-10.0, &schedule));
        assert!(!s.observe(-5.0, &schedule)); // progress
        assert!(!s.observe(-4.8, &schedule)); // under 10 %: stall 1
        assert!(!s.observe(-4.7, &schedule)); // stall 2
        assert!(s.observe(-4.7, &schedule)); // stall 3: switch
        assert_eq!(s.level, 1);
        for _ in 0..10 {
            assert!(!s.observe(-1.0, &schedule), "no level beyond the last");
        }
    }
}
