//! The results folder of a run: written as the run goes, so a killed run keeps its history and its
//! best design so far. What is task-specific (the paper's table, a beam's profile, a robot's walk)
//! comes from the task through `amorph::task::Scene`; nothing here names a task.
//!
//! ```text
//! results/<name>/
//!   config.toml           the effective configuration (defaults filled in)
//!   history.csv           per epoch and island: evaluations, wall time, resolution, best and mean
//!                         fitness, the task's figure of the best (a beam's RMS error, a robot's gait)
//!   best_genome.json      the best genome so far (updated whenever it improves)
//!   island-<i>-best.json  each island's best genome at the end
//!   population.json       every island's final population with outcomes
//!   best_voxels.json      the best design voxelized at the final resolution
//!   summary.json, summary.md   the final table
//!   exports/              fabrication files of the best design (STL, 3MF, VXA, SVG layers, PNG,
//!                         smooth STL of the genome's field, slices/ for voxel printing)
//!   island-<i>-best.png   a render of each island's best design
//!   progress_evaluations.png, progress_wall_time.png   the best of each island as the run went
//!   the task's own files  profile.png and profile.csv (beam); animation.gif, trajectory.png and
//!                         trajectory.csv (robot)
//!   report.md, report.html     the run report: config, pictures, the paper-style table, links
//! ```

mod finishing;
mod plots;
mod report;
mod writer;

pub use finishing::FinerCheck;
pub use writer::ResultWriter;
