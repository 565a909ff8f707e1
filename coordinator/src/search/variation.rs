//! The local climb: a share of each epoch's children are nudges of the best design instead of
//! crossover children. Off in the paper's search (`fraction = 0`); the `climb` preset's default.
//! It puts no state into the genome, which goes over the wire as points only, and the
//! combination it carries between epochs is a function of the outcomes, so a resumed run that
//! replays the same outcomes rebuilds it bit for bit.

use serde::{Deserialize, Serialize};

use super::insertion::BoundarySite;

/// A (1+λ) evolution strategy inside crowding: some children of every epoch are the island's best
/// design with its continuous parameters nudged (no crossover, no material change, no point added
/// or removed). Their dominant parent is the best's slot, so crowding keeps a nudge only if it is
/// fitter than the best.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LocalSearchParams {
    /// Share of each epoch's children that are nudges of the best (0: off, the paper's search).
    pub fraction: f64,
    /// The share at the finest resolution level, where it differs (unset: `fraction`). Under a
    /// shared climb the crossover children there almost never beat the run's best, so their
    /// evaluations can go to the climb instead.
    pub finest_fraction: Option<f64>,
    /// How many of the best's points a nudge moves, every continuous parameter of each; 0 moves
    /// each parameter of every point with `probability` instead. One point changes one region of
    /// the design, which near a good design improves it far more often.
    pub points: usize,
    /// With `points = 0`: the probability that each continuous parameter of each point is nudged.
    pub probability: f64,
    /// Standard deviation of a nudge, as a fraction of the parameter's range (0.02 of the beam's
    /// length is 0.8 of a voxel along it at 12x40x12).
    pub step: f64,
    /// Share of the nudges that instead add one narrow point at a random voxel on the best's
    /// design boundary, giving that voxel another state (see `search::insertion`).
    pub insertion: f64,
    /// Every island's nudges start from the run's best (in the island that holds it, which judges
    /// them) instead of the island's own best: one climb fed by all islands rather than one short
    /// climb per island. Crossover children stay in their islands.
    pub shared: bool,
    /// The nudges of an epoch that beat the design they were nudged from are applied together
    /// (each moved point from the fittest nudge that moved it, inserted points appended) and
    /// offered as the first nudge of the next epoch (`search::combination`): the climb can then
    /// take several steps per epoch instead of one.
    pub combine: bool,
}

impl Default for LocalSearchParams {
    fn default() -> Self {
        Self {
            fraction: 0.0,
            finest_fraction: None,
            points: 1,
            probability: 0.2,
            step: 0.02,
            insertion: 0.0,
            shared: false,
            combine: false,
        }
    }
}

impl LocalSearchParams {
    /// These keys as they act at a level: at the finest, `finest_fraction` replaces `fraction`.
    pub fn at_level(&self, finest: bool) -> Self {
        let fraction = match self.finest_fraction {
            Some(f) if finest => f,
            _ => self.fraction,
        };
        Self {
            fraction,
            ..self.clone()
        }
    }

    /// How many of `count` children are nudges of the best (the rest are bred as in the paper).
    pub fn nudges(&self, count: usize) -> usize {
        ((self.fraction * count as f64).round() as usize).min(count)
    }

    /// Where the insertions of nudges from `genome` go at `dims`, or `None` when insertion is off.
    pub fn boundary_site(
        &self,
        genome: &amorph::genome::Genome,
        scene: &amorph::task::Scene,
        dims: amorph::voxel::GridDims,
    ) -> Option<BoundarySite> {
        (self.insertion > 0.0).then(|| BoundarySite::new(genome, scene, dims))
    }

    /// Moves `genome`, a copy of the island's best, as configured: with probability `insertion`
    /// a point inserted at `site` (the best's design; `None` when insertion is off), else a nudge.
    /// The insertion draw is skipped when it is off, so earlier configs keep their RNG stream.
    pub fn step_from_best<R: rand::Rng + ?Sized>(
        &self,
        genome: &mut amorph::genome::Genome,
        rng: &mut R,
        site: Option<&BoundarySite>,
        scene: &amorph::task::Scene,
    ) {
        let inserted = site.is_some_and(|site| {
            rand::RngExt::random_bool(rng, self.insertion)
                && site.insert(genome, rng, scene).is_some()
        });
        if inserted {
            return;
        }
        if self.points == 0 {
            amorph::genome::perturb(genome, rng, self.probability, self.step, scene.limits());
        } else {
            amorph::genome::perturb_points(genome, rng, self.points, self.step, scene.limits());
        }
    }

    /// Checks every field, naming the first bad one as its config key.
    pub fn validate(&self) -> Result<(), String> {
        let unit = |v: f64| (0.0..=1.0).contains(&v);
        if !unit(self.fraction) {
            return Err("search.local_search.fraction must be in [0, 1]".into());
        }
        if self.finest_fraction.is_some_and(|f| !unit(f)) {
            return Err("search.local_search.finest_fraction must be in [0, 1]".into());
        }
        if !unit(self.probability) {
            return Err("search.local_search.probability must be in [0, 1]".into());
        }
        if !unit(self.insertion) {
            return Err("search.local_search.insertion must be in [0, 1]".into());
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err("search.local_search.step must be a positive number".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
