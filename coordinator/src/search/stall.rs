//! Progress that stalls: epochs in a row in which the run's best improved by less than a set
//! fraction of its own magnitude. The resolution schedule moves to a finer level on a stall, and
//! islands on demand split the population on one (`search.split_after_stall`); both read the same
//! rule so that "stalled" means one thing in a config.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stall {
    best_at_last_progress: f64,
    epochs_without_progress: usize,
}

impl Stall {
    pub fn new() -> Self {
        Self {
            best_at_last_progress: f64::NEG_INFINITY,
            epochs_without_progress: 0,
        }
    }

    /// Records the best fitness after an epoch; returns how many epochs in a row have now passed
    /// without the best rising by more than `min_improvement` times its magnitude at the last
    /// progress. The first observation is always progress.
    pub fn observe(&mut self, best: f64, min_improvement: f64) -> usize {
        let threshold =
            self.best_at_last_progress + min_improvement * self.best_at_last_progress.abs();
        if best > threshold || !self.best_at_last_progress.is_finite() {
            self.best_at_last_progress = best;
            self.epochs_without_progress = 0;
        } else {
            self.epochs_without_progress += 1;
        }
        self.epochs_without_progress
    }
}

impl Default for Stall {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests;
