//! Dynamic analysis: the voxel soft-body simulator (paper §II-B). It knows nothing of fitness: the
//! locomotion task (`crate::task::locomotion`) runs its protocol on it.
//!
//! Voxels carry position, orientation, momentum and angular momentum in flat arrays; links between
//! face-adjacent voxels are co-rotational 3-D Euler–Bernoulli frame elements; semi-implicit Euler
//! advances the state with an automatic time step. The scene ([`DynamicScene`]) decides which
//! passes the step loop has (links, gravity, floor with Coulomb friction, self-collision,
//! actuation, each damping kind); a disabled pass is absent from the loop.
//!
//! Divergence is an outcome ([`Divergence`]), never a panic, and the simulation is
//! bit-reproducible: on one thread, or inside a `rayon` thread pool on its threads with the same
//! bits for any number of them ([`Simulation::step`]).

mod collide;
mod error;
mod integrate;
mod lanes;
mod link;
mod link_ends;
mod link_frame;
mod math;
mod parallel;
mod passes;
mod poisson;
mod scene;
mod simulation;
mod single;
mod single_lanes;
mod state;

pub use error::{DynamicsError, Result};
pub use math::{Mat3, Quat, Vec3};
pub use parallel::EvaluationThreads;
pub use scene::{
    Actuation, DampingParams, DivergenceLimits, DynamicScene, Floor, FrictionLaw, LinkPrecision,
    foam_palette,
};
pub use simulation::{Divergence, DivergenceReason, Energy, Pass, Simulation};
pub use state::TOP_EIGENVALUE;
