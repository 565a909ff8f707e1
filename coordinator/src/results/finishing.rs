//! The end-of-run work `[export]` asks for beyond the fabrication files: the check that the best
//! design still works when simulated twice as finely (a design that only works because of its
//! voxel grid would not survive printing).

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::GridDims;
use serde::Serialize;

/// The best design at the run's final resolution and at twice it per axis.
#[derive(Clone, Debug, Serialize)]
pub struct FinerCheck {
    pub resolution: String,
    pub finer_resolution: String,
    pub fitness: Option<f64>,
    pub finer_fitness: Option<f64>,
    /// The task's figure (a beam's RMS error, a robot's speed), which unlike the fitness means the
    /// same at every resolution (a beam's fitness sums over its stations, twice as many here).
    pub figure: &'static str,
    pub value: Option<f64>,
    pub finer_value: Option<f64>,
    /// Of the figure, (finer − final) / |final|; absent when either is missing or final is 0.
    pub relative_change: Option<f64>,
    pub headline: Option<String>,
    pub finer_headline: Option<String>,
    /// Why the finer evaluation was not made (it would not fit the memory budget) or failed.
    pub note: Option<String>,
}

impl FinerCheck {
    /// Evaluates `genome` at twice `dims` (the run's own outcome at `dims` is `outcome`). A grid
    /// that would not fit a worker's memory budget is skipped with a note, not attempted.
    pub fn run(scene: &Scene, genome: &Genome, dims: GridDims, outcome: &Outcome) -> Self {
        let finer = GridDims::new(2 * dims.nx, 2 * dims.ny, 2 * dims.nz);
        let mut check = FinerCheck {
            resolution: dims.to_string(),
            finer_resolution: finer.to_string(),
            fitness: outcome.fitness(),
            finer_fitness: None,
            figure: scene.figure_spec().column,
            value: scene.figure(outcome),
            finer_value: None,
            relative_change: None,
            headline: scene.headline(outcome),
            finer_headline: None,
            note: None,
        };
        let refusal = match scene.check_dims(finer) {
            Err(e) => Some(e.to_string()),
            Ok(()) => {
                amorph::task::memory::check(scene, finer, amorph::task::memory::default_budget())
                    .err()
                    .map(|e| e.to_string())
            }
        };
        if let Some(e) = refusal {
            check.note = Some(format!("not evaluated at {finer}: {e}"));
            return check;
        }
        let finer_outcome = scene.evaluate(genome, finer);
        check.finer_fitness = finer_outcome.fitness();
        check.finer_headline = scene.headline(&finer_outcome);
        check.finer_value = scene.figure(&finer_outcome);
        check.relative_change = match (check.value, check.finer_value) {
            (Some(a), Some(b)) if a != 0.0 => Some((b - a) / a.abs()),
            _ => None,
        };
        if let Outcome::Failed { failure } = &finer_outcome {
            check.note = Some(format!("the evaluation at {finer} failed: {failure}"));
        }
        check
    }

    /// One paragraph for the report.
    pub fn sentence(&self) -> String {
        if let Some(note) = &self.note
            && self.finer_fitness.is_none()
        {
            return format!("The best design was {note}.");
        }
        let show = |h: &Option<String>, f: Option<f64>| {
            h.clone()
                .unwrap_or_else(|| f.map_or("no fitness".into(), |f| format!("fitness {f:e}")))
        };
        format!(
            "Simulated twice as finely ({} instead of {}), the best design gives {} (at {}: {}); its figure `{}` changes by {} of its value. A large change means the design relies on its voxel grid and may not work as printed.",
            self.finer_resolution,
            self.resolution,
            show(&self.finer_headline, self.finer_fitness),
            self.resolution,
            show(&self.headline, self.fitness),
            self.figure,
            self.relative_change
                .map_or("an unknown amount".into(), |c| format!(
                    "{:+.1} %",
                    100.0 * c
                )),
        )
    }
}
