//! The evolutionary search: deterministic-crowding islands bred in epochs, migration between them,
//! and the multi-resolution schedule.

mod island;
mod migration;
mod resolution;

pub use island::{Breeding, Child, Individual, Island};
pub use migration::{
    ArrivalReplacement, EmigrantSelection, MigrationEvent, MigrationParams, Topology,
    genome_distance, migrate,
};
pub use resolution::{ResolutionSchedule, ResolutionState};
