//! The shared crate's tests as one binary (one link instead of one per file): the physics
//! against analytic solutions and Voxelyze, the genome's properties, the exports read back, and
//! the tasks' fitness.

mod common;
mod dynamics_cantilever;
mod dynamics_conservation;
mod dynamics_floor_actuation;
mod dynamics_mixed_precision;
mod dynamics_poisson;
mod dynamics_stability;
mod dynamics_threads;
mod export_3mf;
mod export_layers;
mod export_mesh;
mod export_print;
mod export_render;
mod export_smooth;
mod export_voxcraft;
mod export_vxa;
mod genome_properties;
mod locomotion_pictures;
mod statics_accuracy;
mod statics_instruction_set;
mod statics_props;
mod task_beam_targets;
mod task_locomotion_heading;
mod task_locomotion_settle;
mod task_locomotion_starts;
mod task_objectives;
mod task_stiffness;
