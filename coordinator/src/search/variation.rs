//! Variation policies beyond the paper's operators, each off by default so a config that does not
//! name them breeds exactly as the paper does: a local search around each island's best design,
//! a mutation step that adapts to each island's success (the 1/5th rule), and crossover planes
//! across the beam.
//!
//! None of them puts state into the genome, which goes over the wire as points only: the adapted
//! step lives in the island and is a function of the replacements so far, so a resumed run that
//! replays the same outcomes rebuilds it bit for bit.

use amorph::genome::GenomeLimits;
use serde::{Deserialize, Serialize};

use super::combination::{CombineBy, Combining};
use super::insertion::{BoundarySite, InsertionBy, MAX_MODEL_STEPS};

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
    /// shared climb the crossover children there never beat the run's best in the arc's runs
    /// (docs/evolution.md, session 38), so their evaluations can go to the climb instead.
    pub finest_fraction: Option<f64>,
    /// How many of the best's points a nudge moves, every continuous parameter of each; 0 moves
    /// each parameter of every point with `probability` instead. One point changes one region of
    /// the design, which near a good design improves it far more often (docs/evolution.md).
    pub points: usize,
    /// With `points = 0`: the probability that each continuous parameter of each point is nudged.
    pub probability: f64,
    /// Standard deviation of a nudge, as a fraction of the parameter's range (0.02 of the beam's
    /// length is 0.8 of a voxel along it at 12x40x12).
    pub step: f64,
    /// Each nudge's step is `step` times 2^u, u drawn uniformly from [-spread, spread] (0: always
    /// `step`, no draw). A stalled climb needs moves of another size than the one it climbed
    /// with; a spread of scales offers every size in every epoch without a state to adapt.
    pub step_spread: f64,
    /// Share of the nudges that instead add one narrow point at a random voxel on the best's
    /// design boundary, giving that voxel another state (see `search::insertion`).
    pub insertion: f64,
    /// Where insertions go: `random` (a uniformly random boundary voxel and other state) or
    /// `flip_model` (a boundary change drawn by the gain the task's model of single-voxel changes
    /// predicts from the best's measured outcome; beams only).
    pub insertion_by: InsertionBy,
    /// With `insertion_by = "flip_model"`: how many of each epoch's nudges are the model's steps
    /// instead, the best with the first 1, 2, 4, ... changes of the flip model's greedy sequence
    /// of boundary changes appended (0: none, at most 8). The model adds up single-voxel changes
    /// knowing what each one before it fixed, where the improving nudges' combination cannot.
    pub model_steps: usize,
    /// Every island's nudges start from the run's best (in the island that holds it, which judges
    /// them) instead of the island's own best: one climb fed by all islands rather than one short
    /// climb per island. Crossover children stay in their islands.
    pub shared: bool,
    /// With `shared`: `fraction` is the share of the whole epoch's children, spread over the
    /// islands as the budget is (the first islands take the remainder), instead of each island's
    /// share rounded on its own. Three children at 0.5 round to two nudges, so sixteen islands of
    /// 3 gave the climb 32 of 48 children where one island of 48 gives it 24; with this the
    /// climb's share is the configured one whatever the island count.
    pub per_epoch: bool,
    /// The nudges of an epoch that beat the design they were nudged from are applied together
    /// (each moved point from the fittest nudge that moved it, inserted points appended) and
    /// offered as the first nudge of the next epoch (`search::combination`): the climb can then
    /// take several steps per epoch instead of one.
    pub combine: bool,
    /// With `combine`: which nudges are added up, `fitness` (every improving one, fittest first)
    /// or `residuals` (those a linear model of the task's residuals picks, among all of the
    /// epoch's nudges: `search::residual_model`).
    pub combine_by: CombineBy,
    /// With `combine_by = "least_squares"`: how far from zero each nudge's coefficient may go
    /// (1: a nudge at most taken whole or reversed).
    pub reach: f64,
    /// With `combine`: how many combined designs an epoch offers, all the improving nudges, then
    /// the fittest half, quarter, ... (distinct ones only; 1: all of them, the session-13 rule).
    pub combinations: usize,
    /// With `combine`: the combined designs are built on the design that holds the nudges' slot
    /// after the epoch (a point it changed keeps its change) instead of the one they started from.
    pub rebase: bool,
}

impl Default for LocalSearchParams {
    fn default() -> Self {
        Self {
            fraction: 0.0,
            finest_fraction: None,
            points: 1,
            probability: 0.2,
            step: 0.02,
            step_spread: 0.0,
            insertion: 0.0,
            insertion_by: InsertionBy::Random,
            model_steps: 0,
            shared: false,
            per_epoch: false,
            combine: false,
            combine_by: CombineBy::Fitness,
            reach: 1.0,
            combinations: 1,
            rebase: false,
        }
    }
}

impl LocalSearchParams {
    /// How an epoch's improving nudges are added up, or `None` without `combine`.
    pub fn combining(&self, limits: &GenomeLimits) -> Option<Combining> {
        self.combine.then_some(Combining {
            by: self.combine_by,
            limits: *limits,
            reach: self.reach,
            combinations: self.combinations,
            rebase: self.rebase,
        })
    }

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

    /// How many of each island's `counts` children are nudges: each island's own share, or with
    /// `per_epoch` the epoch's share spread as evenly as the counts allow, lower indices first.
    pub fn nudges_per_island(&self, counts: &[usize]) -> Vec<usize> {
        if !self.per_epoch {
            return counts.iter().map(|&c| self.nudges(c)).collect();
        }
        let mut left = self.nudges(counts.iter().sum());
        let mut nudges = vec![0; counts.len()];
        // Round-robin one nudge at a time: an island whose count the budget cut short takes
        // fewer, and the others take its share, so the epoch's total is kept. `nudges` never
        // exceeds the children it is given, so every round deals at least one and this ends.
        while left > 0 {
            for (n, &c) in nudges.iter_mut().zip(counts) {
                if left > 0 && *n < c {
                    *n += 1;
                    left -= 1;
                }
            }
        }
        nudges
    }

    /// Where the insertions of nudges from `genome` (evaluated to `outcome` at `dims`) go, or
    /// `None` when insertion is off.
    pub fn boundary_site(
        &self,
        genome: &amorph::genome::Genome,
        outcome: &amorph::task::Outcome,
        scene: &amorph::task::Scene,
        dims: amorph::voxel::GridDims,
    ) -> Option<BoundarySite> {
        (self.insertion > 0.0).then(|| {
            let site = BoundarySite::new(genome, scene, dims);
            match (self.insertion_by, self.model_steps) {
                (InsertionBy::Random, _) => site,
                (InsertionBy::FlipModel, 0) => site.guided_by(scene, outcome),
                // The longest of `model_steps` children takes 2^(model_steps - 1) changes.
                (InsertionBy::FlipModel, steps) => site.guided_by(scene, outcome).with_model_step(
                    genome,
                    scene,
                    outcome,
                    1 << (steps - 1),
                ),
            }
        })
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
        let step = self.nudge_step(rng);
        if self.points == 0 {
            amorph::genome::perturb(genome, rng, self.probability, step, scene.limits());
        } else {
            amorph::genome::perturb_points(genome, rng, self.points, step, scene.limits());
        }
    }

    /// One nudge's step: `step`, scaled log-uniformly within `step_spread` octaves when that is
    /// set (a spread of 0 draws nothing, so earlier configs keep their RNG stream).
    fn nudge_step<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        if self.step_spread == 0.0 {
            return self.step;
        }
        let octaves = rand::RngExt::random_range(rng, -self.step_spread..=self.step_spread);
        self.step * octaves.exp2()
    }
}

/// How an island's mutation step changes from epoch to epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepRule {
    /// The configured step throughout (the paper).
    #[default]
    Fixed,
    /// Rechenberg's 1/5th success rule: after an epoch in which more than a fifth of the children
    /// replaced their dominant parent the step grows by `factor`, after one with fewer it shrinks
    /// by it, within [`StepAdaptation::min_scale`, `StepAdaptation::max_scale`].
    OneFifth,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StepAdaptation {
    pub rule: StepRule,
    /// Growth or shrinkage of the step per epoch (> 1).
    pub factor: f64,
    /// Bounds on the step as a multiple of `search.mutation.step`.
    pub min_scale: f64,
    pub max_scale: f64,
}

impl Default for StepAdaptation {
    fn default() -> Self {
        Self {
            rule: StepRule::Fixed,
            factor: 1.2,
            min_scale: 0.1,
            max_scale: 4.0,
        }
    }
}

/// A coefficient of a few nudges is already far outside where a voxelized design changes
/// linearly; beyond this the model's step means nothing.
const MAX_REACH: f64 = 8.0;

/// More combined designs than this would halve the fittest nudge down to one long before.
const MAX_COMBINATIONS: usize = 16;

/// Six octaves either way already spans 1/64 to 64 times the step: a nudge of 0.02 of a range
/// would reach beyond the whole range, and at the other end move nothing a voxel can see.
const MAX_STEP_SPREAD: f64 = 6.0;

/// The success rate that separates growing from shrinking under the 1/5th rule.
const ONE_FIFTH: f64 = 0.2;

impl StepAdaptation {
    /// The next epoch's scale of the mutation step, given this epoch's scale and how many of its
    /// `tried` children replaced their dominant parent. An epoch without children keeps the scale.
    pub fn next_scale(&self, scale: f64, replaced: usize, tried: usize) -> f64 {
        if self.rule == StepRule::Fixed || tried == 0 {
            return scale;
        }
        let rate = replaced as f64 / tried as f64;
        let next = if rate > ONE_FIFTH {
            scale * self.factor
        } else if rate < ONE_FIFTH {
            scale / self.factor
        } else {
            scale
        };
        next.clamp(self.min_scale, self.max_scale)
    }
}

/// Where crossover cuts.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CrossoverParams {
    /// Probability that a cut plane is across `axis` instead of uniformly oriented (0: the paper).
    pub across_probability: f64,
    /// The axis such planes cut across (0 = x, 1 = y, the beam's length, 2 = z).
    pub axis: usize,
}

impl Default for CrossoverParams {
    fn default() -> Self {
        Self {
            across_probability: 0.0,
            axis: 1,
        }
    }
}

/// The variation policies of a run (`[search.local_search]`, `[search.step_adaptation]`,
/// `[search.crossover]`), checked before a run starts.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Variation {
    pub local_search: LocalSearchParams,
    pub step_adaptation: StepAdaptation,
    pub crossover: CrossoverParams,
}

impl Variation {
    /// Checks every field, naming the first bad one as its config key.
    pub fn validate(&self) -> Result<(), String> {
        let unit = |v: f64| (0.0..=1.0).contains(&v);
        let l = &self.local_search;
        if !unit(l.fraction) {
            return Err("search.local_search.fraction must be in [0, 1]".into());
        }
        if l.finest_fraction.is_some_and(|f| !unit(f)) {
            return Err("search.local_search.finest_fraction must be in [0, 1]".into());
        }
        if !unit(l.probability) {
            return Err("search.local_search.probability must be in [0, 1]".into());
        }
        if !unit(l.insertion) {
            return Err("search.local_search.insertion must be in [0, 1]".into());
        }
        if !(l.step.is_finite() && l.step > 0.0) {
            return Err("search.local_search.step must be a positive number".into());
        }
        // NaN and infinities fall outside the range too.
        if !(0.0..=MAX_STEP_SPREAD).contains(&l.step_spread) {
            return Err(format!(
                "search.local_search.step_spread must be in [0, {MAX_STEP_SPREAD}] (octaves)"
            ));
        }
        if !(1..=MAX_COMBINATIONS).contains(&l.combinations) {
            return Err(format!(
                "search.local_search.combinations must be between 1 and {MAX_COMBINATIONS}"
            ));
        }
        if !(l.reach.is_finite() && l.reach > 0.0 && l.reach <= MAX_REACH) {
            return Err(format!(
                "search.local_search.reach must be in (0, {MAX_REACH}]"
            ));
        }
        if l.reach != 1.0 && l.combine_by != CombineBy::LeastSquares {
            return Err(
                "search.local_search.reach needs search.local_search.combine_by = \"least_squares\"".into(),
            );
        }
        if l.insertion_by != InsertionBy::Random && l.insertion == 0.0 {
            return Err(format!(
                "search.local_search.insertion_by = \"{}\" needs search.local_search.insertion > 0",
                l.insertion_by.key()
            ));
        }
        if l.model_steps > 0 && l.insertion_by != InsertionBy::FlipModel {
            return Err(
                "search.local_search.model_steps needs search.local_search.insertion_by = \"flip_model\"".into(),
            );
        }
        if l.model_steps > MAX_MODEL_STEPS {
            return Err(format!(
                "search.local_search.model_steps must be at most {MAX_MODEL_STEPS}"
            ));
        }
        if l.per_epoch && !l.shared {
            return Err(
                "search.local_search.per_epoch needs shared = true (one climb for the run)".into(),
            );
        }
        if !l.combine && (l.combinations != 1 || l.rebase || l.combine_by != CombineBy::Fitness) {
            return Err(
                "search.local_search.combinations, combine_by and rebase need search.local_search.combine = true"
                    .into(),
            );
        }
        let a = &self.step_adaptation;
        if !(a.factor.is_finite() && a.factor > 1.0) {
            return Err("search.step_adaptation.factor must be a number above 1".into());
        }
        if !(a.min_scale.is_finite() && a.min_scale > 0.0 && a.min_scale <= 1.0) {
            return Err("search.step_adaptation.min_scale must be in (0, 1]".into());
        }
        if !(a.max_scale.is_finite() && a.max_scale >= 1.0) {
            return Err("search.step_adaptation.max_scale must be at least 1".into());
        }
        let c = &self.crossover;
        if !unit(c.across_probability) {
            return Err("search.crossover.across_probability must be in [0, 1]".into());
        }
        if c.axis > 2 {
            return Err("search.crossover.axis must be 0 (x), 1 (y) or 2 (z)".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
