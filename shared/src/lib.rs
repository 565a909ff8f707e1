//! Amorph's science, with no networking: Gaussian-mixture genomes, voxelization, the static
//! direct-stiffness solver, the dynamic voxel soft-body simulator, the tasks built on them, the
//! fabrication exports and the run's figures. Everything here is a pure function of its inputs: the same genome, scene and
//! resolution give the same bits on any machine.

pub mod dynamics;
pub mod export;
pub mod genome;
pub mod heap;
pub mod material;
pub mod outcome;
pub mod report;
pub mod statics;
pub mod task;
pub mod voxel;
