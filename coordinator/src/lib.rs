//! The Amorph coordinator: reads a run configuration, keeps the island populations, hands genomes to
//! an evaluator (local threads, or gRPC workers), applies deterministic crowding and migration, and
//! writes the results folder.

pub mod config;
pub mod evaluator;
pub mod ids;
pub mod progress;
pub mod results;
pub mod run;
pub mod search;

pub use config::RunConfig;
pub use evaluator::{Evaluator, LocalEvaluator, Task};
pub use run::{RunSummary, StopReason, run};
