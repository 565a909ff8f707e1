//! The beam designer's task (paper §III): cantilevers that deflect into a prescribed profile.

mod target;
mod task;

pub use target::TargetProfile;
pub use task::{BeamMetrics, BeamScene, beam_design, evaluate_beam, evaluate_beam_design};
