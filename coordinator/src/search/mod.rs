//! The evolutionary search: deterministic-crowding islands bred in epochs, migration between them,
//! islands on demand, and the multi-resolution schedule.

mod combination;
mod diversity;
#[cfg(test)]
mod fixtures;
mod insertion;
mod island;
mod least_squares;
mod migration;
mod residual_model;
mod resolution;
mod split;
mod stall;
mod step_kind;
mod unchanged;
mod variation;

pub use combination::{CombineBy, Combining};
pub use diversity::{
    DiversityLog, IslandDiversity, design_distance, mean_pairwise_distance, measure,
};
pub use insertion::{BoundarySite, InsertionBy, MAX_MODEL_STEPS, other_state};
pub use island::{Breeding, Child, Individual, Island, SharedBest};
pub use migration::{
    ArrivalReplacement, EmigrantSelection, MigrationEvent, MigrationParams, Topology,
    genome_distance, migrate,
};
pub use resolution::{ResolutionSchedule, ResolutionState, merge_order};
pub use split::{SplitWatch, split_island};
pub use step_kind::{StepKind, step_kind};
pub use unchanged::{ParentDesigns, first_in_turn, keep_at_least_one};
pub use variation::{CrossoverParams, LocalSearchParams, StepAdaptation, StepRule, Variation};
