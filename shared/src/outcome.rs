//! The result of one evaluation. A design that cannot be simulated is an outcome with a reason,
//! never a panic and never a NaN fitness.

use serde::{Deserialize, Serialize};

use crate::beam::BeamMetrics;
use crate::locomotion::LocomotionMetrics;

/// Why an evaluation produced no fitness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(rename_all = "snake_case")]
pub enum Failure {
    #[error("invalid genome: {0}")]
    InvalidGenome(String),
    #[error("invalid request: {0}")]
    InvalidRequest(String),
    #[error("the design has no voxels")]
    Empty,
    #[error("the design does not reach the free-end layer")]
    NotSpanning,
    #[error("solver: {0}")]
    Solver(String),
    #[error("degenerate response: {0}")]
    Degenerate(String),
    #[error("internal error (a bug): {0}")]
    Internal(String),
    #[error("diverged at t = {time} s: {reason}")]
    Diverged { reason: String, time: f64 },
}

/// Task-specific measurements behind a fitness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Metrics {
    Beam(BeamMetrics),
    Locomotion(LocomotionMetrics),
}

/// What a worker returns for a task.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    Evaluated { fitness: f64, metrics: Metrics },
    Failed { failure: Failure },
}

impl Outcome {
    /// An evaluated outcome. A non-finite fitness is turned into a failure, so no NaN ever reaches
    /// the search.
    pub fn evaluated(fitness: f64, metrics: Metrics) -> Self {
        if fitness.is_finite() {
            Self::Evaluated { fitness, metrics }
        } else {
            Self::failed(Failure::Degenerate(format!(
                "fitness {fitness} is not finite"
            )))
        }
    }

    pub fn failed(failure: Failure) -> Self {
        Self::Failed { failure }
    }

    pub fn fitness(&self) -> Option<f64> {
        match self {
            Self::Evaluated { fitness, .. } => Some(*fitness),
            Self::Failed { .. } => None,
        }
    }

    /// A totally ordered key: failures rank below every evaluated design.
    pub fn rank(&self) -> f64 {
        self.fitness().unwrap_or(f64::NEG_INFINITY)
    }

    /// Whether this outcome is strictly fitter than `other` (the crowding replacement rule).
    pub fn is_fitter_than(&self, other: &Outcome) -> bool {
        self.rank() > other.rank()
    }

    pub fn locomotion_metrics(&self) -> Option<&LocomotionMetrics> {
        match self {
            Self::Evaluated {
                metrics: Metrics::Locomotion(m),
                ..
            } => Some(m),
            _ => None,
        }
    }

    /// The task's headline figure for progress lines and summaries: the beam's RMS error, or the
    /// robot's speed.
    pub fn headline(&self) -> Option<String> {
        match self {
            Self::Evaluated {
                metrics: Metrics::Beam(m),
                ..
            } => Some(format!("RMS {:.3} %", m.rms_percent)),
            Self::Evaluated {
                metrics: Metrics::Locomotion(m),
                ..
            } => Some(format!(
                "gait {:.2} mm ({:.2} % body length/cycle), travel {:.2} mm",
                1e3 * m.gait_displacement,
                m.speed_percent_per_cycle,
                1e3 * m.displacement
            )),
            Self::Failed { .. } => None,
        }
    }

    pub fn beam_metrics(&self) -> Option<&BeamMetrics> {
        match self {
            Self::Evaluated {
                metrics: Metrics::Beam(m),
                ..
            } => Some(m),
            _ => None,
        }
    }
}
