//! One evaluation: genome + scene + resolution → outcome. Pure and deterministic.

use crate::beam::evaluate_beam;
use crate::genome::Genome;
use crate::locomotion::evaluate_locomotion;
use crate::outcome::Outcome;
use crate::scene::Scene;
use crate::voxel::GridDims;

/// Evaluates `genome` in `scene` at resolution `dims`.
pub fn evaluate(genome: &Genome, scene: &Scene, dims: GridDims) -> Outcome {
    match scene {
        Scene::Beam(beam) => evaluate_beam(genome, beam, dims),
        Scene::Locomotion(scene) => evaluate_locomotion(genome, scene, dims),
    }
}
