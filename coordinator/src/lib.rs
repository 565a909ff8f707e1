//! The Amorph coordinator: reads a run configuration, keeps the island populations, hands genomes to
//! an evaluator (local threads, or gRPC workers), applies deterministic crowding and migration, and
//! writes the results folder.

pub mod asked;
pub mod cluster;
pub mod config;
pub mod dashboard;
pub mod evaluator;
pub use amorph_proto::ids;
pub mod job;
pub mod principal;
pub mod progress;
pub mod results;
pub mod run;
pub mod search;
pub mod store;
pub mod summary;
pub mod verification;

pub use config::RunConfig;
pub use evaluator::{Evaluator, LocalEvaluator, Task};
pub use job::{JobOptions, StoreMode, run_job};
pub use run::{RunContext, run};
pub use summary::{RunSummary, StopReason};
