//! The result of one evaluation, generic over the task's measurements: a design that cannot be
//! simulated is an outcome with a reason, never a panic and never a NaN fitness. The tasks
//! (`crate::task`) fill in the metrics; nothing here knows what they are.

use serde::{Deserialize, Deserializer, Serialize};

use crate::dynamics::DivergenceReason;

/// Why an evaluation produced no fitness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(rename_all = "snake_case")]
pub enum Failure {
    #[error("invalid genome: {0}")]
    InvalidGenome(String),
    #[error("invalid request: {0}")]
    InvalidRequest(String),
    /// No voxel the task can use: a beam keeps only what is connected to its clamped layer, so a
    /// design whose root layer comes out empty at some resolution is empty there.
    #[error(
        "the design has no voxels the task can use (a beam: none connected to its clamped layer)"
    )]
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
    Diverged {
        #[serde(deserialize_with = "divergence_reason")]
        reason: DivergenceReason,
        time: f64,
    },
}

/// A stored divergence reason: the typed form, or the sentence that run stores written before the
/// reason was typed hold in its place (its numbers as printed, to three decimals for the measured
/// value). A sentence of any other shape is refused, naming it.
fn divergence_reason<'de, D: Deserializer<'de>>(d: D) -> Result<DivergenceReason, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Stored {
        Typed(DivergenceReason),
        Sentence(String),
    }
    match Stored::deserialize(d)? {
        Stored::Typed(reason) => Ok(reason),
        Stored::Sentence(text) => reason_from_sentence(&text)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown divergence reason {text:?}"))),
    }
}

fn reason_from_sentence(text: &str) -> Option<DivergenceReason> {
    let number = |s: &str| s.trim().parse::<f64>().ok();
    if text == "non-finite state" {
        return Some(DivergenceReason::NonFinite);
    }
    if let Some(rest) = text.strip_prefix("link strain ") {
        let (strain, limit) = rest.split_once(" above the limit ")?;
        return Some(DivergenceReason::Strain {
            strain: number(strain)?,
            limit: number(limit)?,
        });
    }
    let rest = text.strip_prefix("a voxel moved ")?;
    let (travel, limit) = rest.split_once(" voxel sizes in one step, above the limit ")?;
    Some(DivergenceReason::Runaway {
        travel: number(travel)?,
        limit: number(limit)?,
    })
}

/// What an evaluation returns: a fitness with the task's measurements `M` behind it, or a failure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome<M> {
    Evaluated { fitness: f64, metrics: M },
    Failed { failure: Failure },
}

impl<M> Outcome<M> {
    /// An evaluated outcome. A non-finite fitness is turned into a failure, so no NaN ever reaches
    /// the search.
    pub fn evaluated(fitness: f64, metrics: M) -> Self {
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
    pub fn is_fitter_than<N>(&self, other: &Outcome<N>) -> bool {
        self.rank() > other.rank()
    }

    /// The measurements of an evaluated design.
    pub fn metrics(&self) -> Option<&M> {
        match self {
            Self::Evaluated { metrics, .. } => Some(metrics),
            Self::Failed { .. } => None,
        }
    }

    /// The same outcome with its measurements mapped, e.g. a task's own metrics into the
    /// registry's enum.
    pub fn map<N>(self, f: impl FnOnce(M) -> N) -> Outcome<N> {
        match self {
            Self::Evaluated { fitness, metrics } => Outcome::Evaluated {
                fitness,
                metrics: f(metrics),
            },
            Self::Failed { failure } => Outcome::Failed { failure },
        }
    }
}

#[cfg(test)]
mod tests;
