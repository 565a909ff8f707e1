//! A task's prediction of what changing one voxel does to its fitness: what lets a local search
//! change the voxels its error asks for rather than random ones on the design's boundary. The
//! physics knows nothing of fitness; a task that can model both (a beam's profile against its
//! layers' stiffness) offers one, built from a design and the metrics its evaluation measured.

use crate::material::MaterialId;

/// Predicted gains of single-voxel changes to one design.
pub trait FlipModel {
    /// How much the fitness is expected to rise when `cell` (an index of the design's grid) takes
    /// the state `to` (empty or a material); negative for a change expected to hurt, minus
    /// infinity for one the task could not evaluate (a beam cut in two).
    fn gain(&self, cell: usize, to: Option<MaterialId>) -> f64;
    /// Takes that change as made: later gains are predicted for the design with it (a change
    /// that cannot be evaluated is not taken).
    fn take(&mut self, cell: usize, to: Option<MaterialId>);
}
