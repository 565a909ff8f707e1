//! The evolutionary search: deterministic-crowding islands bred in epochs, migration between them,
//! the local climb around the best design, and the multi-resolution schedule.

mod combination;
mod diversity;
#[cfg(test)]
#[path = "tests/fixtures.rs"]
mod fixtures;
mod insertion;
mod island;
mod migration;
mod objectives;
mod pareto;
mod resolution;
mod stall;
mod unchanged;
mod variation;

pub use diversity::{
    DiversityLog, IslandDiversity, design_distance, mean_pairwise_distance, measure,
};
pub use insertion::{BoundarySite, other_state};
pub use island::{Breeding, Child, Individual, Island, SharedBest};
pub use migration::{
    ArrivalReplacement, EmigrantSelection, MigrationEvent, MigrationParams, Topology,
    genome_distance, migrate,
};
pub use objectives::{Front, Pareto, Selection, Standing, stands_better};
pub use pareto::{crowding_distances, dominates, front_ranks, fronts, hypervolume};
pub use resolution::{ResolutionSchedule, ResolutionState};
pub use unchanged::{ParentDesigns, first_in_turn, keep_at_least_one};
pub use variation::LocalSearchParams;
