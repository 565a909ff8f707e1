//! Static analysis: the linear direct-stiffness method on a voxel frame (paper §II-A).
//!
//! Every filled voxel is a node with six DOF; every face-adjacent pair is an Euler–Bernoulli
//! frame element ([`StaticModel`]). [`solve`] removes the fixed nodes, assembles the free nodes'
//! stiffness in 6×6 block sparse form and solves `K u = f` directly (faer's sparse Cholesky) or by
//! preconditioned conjugate gradients, as [`StaticSolverParams`] chooses. See
//! `docs/explanation/physics.md` for the model, the measured solver comparison and the accuracy
//! tests.

mod amg;
mod bsr;
mod direct;
mod element;
mod error;
mod model;
mod params;
mod pcg;
mod single;
mod solve;
mod spgemm;
mod system;
mod wide;

pub use error::{Result, StaticsError};
pub use model::StaticModel;
pub use params::{MultigridParams, Preconditioner, SolverMethod, StaticSolverParams};
pub use solve::{
    SolveDiagnostics, SolveMethodUsed, StaticLoadCase, StaticSolution, StaticSolver, solve,
};
pub use wide::baseline_only;
