//! Point insertion at the design's boundary: a local-search move that changes the island's best
//! design by about one voxel, by adding one small Gaussian point to its genome.
//!
//! Near a good design, moving whole points stalls (docs/evolution.md: from a circular-arc beam at
//! 0.124 % RMS, one-point nudges reach 0.10 % in 2,000 evaluations), while flipping single voxels
//! on the design's boundary keeps improving it (0.057 % in 1,500 flips). The genome cannot name a
//! voxel, but it can add a point there: at the narrowest falloff a point's Gaussian is about a
//! voxel wide, and its density is chosen from the field at that voxel so that the voxel takes the
//! chosen state and its neighbours change only where they were already close to changing. The
//! design stays a Gaussian mixture, sampled the same way at any resolution and by the print.

use amorph::genome::{GaussianPoint, Genome};
use amorph::material::MaterialId;
use amorph::task::Scene;
use amorph::voxel::{GridDims, VoxelGrid, density_fields};
use rand::Rng;
use rand::RngExt;

/// Where a local search's insertions go (`[search.local_search]` `insertion_by`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InsertionBy {
    /// A uniformly random boundary voxel, a uniformly random other state (session 7).
    #[default]
    Random,
    /// A boundary change drawn by the gain the task's flip model predicts for it (a beam's
    /// linked cantilever, `amorph::task::beam::BeamFlipModel`); a task without one cannot use it.
    FlipModel,
}

impl InsertionBy {
    /// The rule as the config writes it.
    pub fn key(self) -> &'static str {
        match self {
            InsertionBy::Random => "random",
            InsertionBy::FlipModel => "flip_model",
        }
    }
}

/// Most model-step children an epoch: the longest then takes 2^7 = 128 changes.
pub const MAX_MODEL_STEPS: usize = 8;

/// How far past the threshold (or past the competing material) an inserted point pushes its
/// voxel's field, in density units: enough that rounding never undoes it, small against the
/// densities of [-1, 1] so neighbours move as little as possible.
const MARGIN: f64 = 0.02;

/// The design a genome makes at the run's current resolution, with what an insertion needs of it.
#[derive(Debug)]
pub struct BoundarySite {
    design: VoxelGrid,
    /// Per-material density fields at every voxel centre (material-major).
    fields: Vec<f64>,
    /// Cells whose state differs from one of their neighbours', in index order.
    boundary: Vec<usize>,
    /// With `insertion_by = "flip_model"`: the changes the task's model expects to help.
    guide: Option<Guide>,
    /// With `local_search.model_steps`: the changes the flip model picks one after another, each
    /// the one it expects to help most given those before it (`with_model_step`).
    sequence: Vec<(usize, Option<MaterialId>)>,
}

/// The boundary changes a task's flip model expects to improve the design, each drawn with
/// probability in proportion to its predicted gain: the climb's insertions go where the error is,
/// and still spread over every change that helps rather than repeating the single best one.
#[derive(Debug, PartialEq)]
struct Guide {
    changes: Vec<(usize, Option<MaterialId>)>,
    /// Running sums of the changes' predicted gains, all positive.
    cumulative: Vec<f64>,
}

impl Guide {
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<(usize, Option<MaterialId>)> {
        let total = *self.cumulative.last()?;
        let u = rng.random::<f64>() * total;
        let k = self.cumulative.partition_point(|&c| c <= u);
        self.changes.get(k.min(self.changes.len() - 1)).copied()
    }
}

impl BoundarySite {
    /// Voxelizes `genome` as `scene` does at `dims` and finds its boundary.
    pub fn new(genome: &Genome, scene: &Scene, dims: GridDims) -> Self {
        let design = scene.design(genome, dims);
        let fields = density_fields(genome, dims, scene.palette().len());
        let boundary = design.boundary_cells();
        Self {
            design,
            fields,
            boundary,
            guide: None,
            sequence: Vec::new(),
        }
    }

    /// The same site with its model step: from the design `outcome` measured, the boundary change
    /// the task's flip model expects to help most, taken, then the next given it, and so on while
    /// one is expected to help, each voxel changed at most once, at most `limit` changes (and no
    /// more than the genome has room for), passing over changes no narrow point can make. Without
    /// a model the sequence is empty.
    pub fn with_model_step(
        mut self,
        genome: &Genome,
        scene: &Scene,
        outcome: &amorph::task::Outcome,
        limit: usize,
    ) -> Self {
        let room = scene
            .limits()
            .max_points
            .saturating_sub(genome.points.len());
        let Some(mut model) = scene.flip_model(&self.design, outcome) else {
            return self;
        };
        let mut candidates: Vec<(usize, Option<MaterialId>)> = self.changes(scene).collect();
        let mut sequence = Vec::new();
        while sequence.len() < limit.min(room) {
            // The first of equal gains wins, so the sequence is a function of the design alone.
            let best = (candidates.iter().enumerate())
                .map(|(k, &(cell, to))| (k, model.gain(cell, to)))
                .filter(|&(_, g)| g.is_finite() && g > 0.0)
                .fold(None, |best: Option<(usize, f64)>, (k, g)| match best {
                    Some((_, b)) if b >= g => best,
                    _ => Some((k, g)),
                });
            let Some((k, _)) = best else { break };
            let (cell, to) = candidates[k];
            candidates.remove(k);
            // A change no narrow point can make (its density out of range) is passed over.
            if self.point_for(cell, to, scene).is_none() {
                continue;
            }
            model.take(cell, to);
            sequence.push((cell, to));
            candidates.retain(|&(c, _)| c != cell);
        }
        drop(model);
        self.sequence = sequence;
        self
    }

    /// The same site with its insertions drawn by `scene`'s flip model of the design, read from
    /// `outcome` (the design's evaluation at this site's resolution): each boundary change the
    /// model expects to help, with probability in proportion to its predicted gain. Where the task
    /// has no model, the outcome does not fit the design, or no change is expected to help, the
    /// insertions stay uniform over the boundary.
    pub fn guided_by(mut self, scene: &Scene, outcome: &amorph::task::Outcome) -> Self {
        self.guide = self.guide(scene, outcome);
        self
    }

    fn guide(&self, scene: &Scene, outcome: &amorph::task::Outcome) -> Option<Guide> {
        let model = scene.flip_model(&self.design, outcome)?;
        let (mut changes, mut cumulative, mut total) = (Vec::new(), Vec::new(), 0.0);
        for (cell, to) in self.changes(scene) {
            let gain = model.gain(cell, to);
            if gain.is_finite() && gain > 0.0 {
                total += gain;
                changes.push((cell, to));
                cumulative.push(total);
            }
        }
        (!changes.is_empty()).then_some(Guide {
            changes,
            cumulative,
        })
    }

    /// Every change of one boundary voxel to another state, in cell order, then state order.
    fn changes<'a>(
        &'a self,
        scene: &Scene,
    ) -> impl Iterator<Item = (usize, Option<MaterialId>)> + 'a {
        let materials = scene.palette().len();
        self.boundary.iter().flat_map(move |&cell| {
            let current = self.design.cells()[cell];
            states(materials)
                .filter(move |&s| s != current)
                .map(move |s| (cell, s))
        })
    }

    /// How many boundary changes the flip model expects to help (`None`: unguided).
    pub fn guided_changes(&self) -> Option<usize> {
        self.guide.as_ref().map(|g| g.changes.len())
    }

    /// Adds one point to `genome` (the genome this site was built from) that gives a random
    /// boundary voxel a random other state: empty, or filled with another material (guided: a
    /// change drawn by its predicted gain, see [`BoundarySite::guided_by`]). Returns the
    /// voxel and the state it aims at, or `None`, leaving the genome as it was, when the design
    /// has no boundary, the genome is full, or the density the change needs is outside the
    /// genome's limits.
    pub fn insert<R: Rng + ?Sized>(
        &self,
        genome: &mut Genome,
        rng: &mut R,
        scene: &Scene,
    ) -> Option<(usize, Option<MaterialId>)> {
        let limits = scene.limits();
        if self.boundary.is_empty() || genome.points.len() >= limits.max_points {
            return None;
        }
        let materials = scene.palette().len();
        let (cell, target) = match &self.guide {
            Some(guide) => guide.draw(rng)?,
            None => {
                let cell = self.boundary[rng.random_range(0..self.boundary.len())];
                (cell, other_state(self.design.cells()[cell], materials, rng))
            }
        };
        self.place(genome, cell, target, scene)?;
        Some((cell, target))
    }

    /// Appends the narrow point that gives `cell` the state `target`, or `None`, leaving the
    /// genome as it was, when the density that needs is outside the genome's limits.
    fn place(
        &self,
        genome: &mut Genome,
        cell: usize,
        target: Option<MaterialId>,
        scene: &Scene,
    ) -> Option<()> {
        genome.points.push(self.point_for(cell, target, scene)?);
        Some(())
    }

    /// The narrow point that gives `cell` the state `target` (from the fields of this site's
    /// genome), or `None` when the density that needs is outside the genome's limits.
    fn point_for(
        &self,
        cell: usize,
        target: Option<MaterialId>,
        scene: &Scene,
    ) -> Option<GaussianPoint> {
        let limits = scene.limits();
        let dims = self.design.dims();
        let materials = scene.palette().len();
        let rho: Vec<f64> = (0..materials)
            .map(|k| self.fields[k * dims.cell_count() + cell])
            .collect();
        let total: f64 = rho.iter().sum();
        let threshold = scene.threshold();
        let (material, density) = match target {
            // Carve: bring the total down to the threshold, taking from the densest material.
            None => {
                let densest =
                    (0..materials).fold(0, |best, k| if rho[k] > rho[best] { k } else { best });
                (densest, (threshold - total - MARGIN).min(-MARGIN))
            }
            // Fill with `m`: above the threshold and above every other material.
            Some(m) => {
                let m = m.index();
                let rival = (0..materials)
                    .filter(|&k| k != m)
                    .map(|k| rho[k])
                    .fold(f64::NEG_INFINITY, f64::max);
                let needed = (rival - rho[m]).max(threshold - total).max(0.0) + MARGIN;
                (m, needed)
            }
        };
        if !(limits.density[0]..=limits.density[1]).contains(&density) {
            return None;
        }
        let [x, y, z] = dims.coords(cell);
        Some(GaussianPoint {
            position: dims.normalized_centre(x, y, z),
            density,
            falloff: limits.falloff[0],
            material: MaterialId(material as u8),
        })
    }

    /// The model step's children of `genome` (this site's): the first change of its sequence,
    /// the first two, four, ... up to `count` children (fewer where the sequence is shorter), each
    /// change one appended point; none without a sequence (see [`BoundarySite::with_model_step`]).
    /// The model ranks well and sizes poorly: from an arc design at 0.92 % its first change alone
    /// took the error to 0.84 %, its first eight to 0.67 %, its first sixteen back to 0.83 %, and
    /// from one at 0.25 % its first change made it worse (docs/evolution.md, session 45;
    /// `model_sequence` bench), so the steps grow from one change, not shrink from many.
    pub fn model_step_children(&self, genome: &Genome, scene: &Scene, count: usize) -> Vec<Genome> {
        let lengths: Vec<usize> = (0..count.min(MAX_MODEL_STEPS))
            .map(|k| 1 << k)
            .take_while(|&n| n <= self.sequence.len())
            .collect();
        lengths
            .into_iter()
            .map(|n| {
                let mut child = genome.clone();
                for &(cell, target) in &self.sequence[..n] {
                    // A change whose density is out of range is left out; the others still apply.
                    let _ = self.place(&mut child, cell, target, scene);
                }
                child
            })
            .collect()
    }
}

/// A state other than `current` for one voxel, uniformly among empty and the `materials`.
pub fn other_state<R: Rng + ?Sized>(
    current: Option<MaterialId>,
    materials: usize,
    rng: &mut R,
) -> Option<MaterialId> {
    let others: Vec<Option<MaterialId>> = states(materials).filter(|&s| s != current).collect();
    others[rng.random_range(0..others.len())]
}

/// Every state a voxel can take: empty, then each material.
fn states(materials: usize) -> impl Iterator<Item = Option<MaterialId>> {
    std::iter::once(None).chain((0..materials).map(|m| Some(MaterialId(m as u8))))
}

#[cfg(test)]
#[path = "insertion/tests.rs"]
mod tests;
