//! The Gaussian-mixture genome (paper §I-D, §II): points, limits and validation, and the variation
//! operators of the evolutionary search.

mod operators;
mod point;

pub use operators::{
    Crossover, CutPlane, DominantParent, MutationParams, crossover, mutate, perturb,
    perturb_points, random_genome, random_point,
};
pub use point::{GaussianPoint, Genome, GenomeError, GenomeLimits};
