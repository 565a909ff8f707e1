//! Several starts of one settled robot: the actuation switched on a few times, each time a
//! fraction of a period later, and the median start scored.
//!
//! Why: a walking gait is a chaotic contact problem. Measured on evolved 10³ robots
//! (docs/explanation/physics.md), switching the actuation on 7 µs later (10⁻⁴ of the 0.07 s period)
//! moves the travel of one design by up to a factor of five, more than most fitness differences the
//! search ranks; so a single start rewards the lucky draw, and a design evolved that way may walk
//! far in one simulator at one time step and not in another. The median start is a design's typical
//! gait, and the fitness stays one real simulation's (the median start's), so the reported trace,
//! the pictures and the exported files describe a run that happened. An odd count makes the median
//! one start.

use serde::{Deserialize, Serialize};

use crate::task::SceneError;

/// How many times the settled robot is switched on, and how far apart.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Starts {
    /// Starts from the same settled body, an odd number. Default 1 (the paper's protocol, bit for
    /// bit). Each start costs the actuation cycles again; the settle is shared.
    pub count: u32,
    /// Start k's actuation phase is the scene's plus k·`shift` of a period. Default 1e-3 (70 µs
    /// at the paper's 0.07 s): imperceptible to a robot, yet far enough apart that the starts
    /// are different draws of the gait; at 1e-4 neighbouring starts of a 10³ robot often
    /// agree within 1 % and the median ranks designs little better than one start
    /// (docs/explanation/search.md).
    pub shift: f64,
}

impl Default for Starts {
    fn default() -> Self {
        Self {
            count: 1,
            shift: 1e-3,
        }
    }
}

impl Starts {
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.count.is_multiple_of(2) {
            return Err(SceneError::new(
                "starts.count",
                format!(
                    "{} must be odd (1, 3, 5, …) so that the median is one start's gait",
                    self.count
                ),
            ));
        }
        let span = f64::from(self.count - 1) * self.shift;
        if !(self.shift.is_finite() && self.shift > 0.0 && span < 1.0) {
            return Err(SceneError::new(
                "starts.shift",
                format!(
                    "{} must be a positive fraction of a period, with (count − 1)·shift below 1 \
                     (else the phases wrap round the period)",
                    self.shift
                ),
            ));
        }
        Ok(())
    }

    /// The phase added to the scene's for start `k`, rad.
    pub fn phase(&self, k: usize) -> f64 {
        2.0 * std::f64::consts::PI * k as f64 * self.shift
    }

    /// The start whose fitness is the median of `fitness` (one per start, finite): the middle one
    /// in the order of fitness, ties in the order of starts, so the choice is a function of the
    /// values alone.
    pub fn median_start(fitness: &[f64]) -> usize {
        let mut order: Vec<usize> = (0..fitness.len()).collect();
        order.sort_by(|&a, &b| fitness[a].total_cmp(&fitness[b]).then(a.cmp(&b)));
        order[order.len() / 2]
    }
}

#[cfg(test)]
mod tests;
