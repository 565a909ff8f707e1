//! Point insertion at the design's boundary: a local-search move that changes the island's best
//! design by about one voxel, by adding one small Gaussian point to its genome.
//!
//! Near a good design, moving whole points stalls (from a circular-arc beam at 0.124 % RMS,
//! one-point nudges reached 0.10 % in 2,000 evaluations), while flipping single voxels on the
//! design's boundary kept improving it (0.057 % in 1,500 flips). The genome cannot name a
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
        }
    }

    /// Adds one point to `genome` (the genome this site was built from) that gives a random
    /// boundary voxel a random other state: empty, or filled with another material. Returns the
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
        let cell = self.boundary[rng.random_range(0..self.boundary.len())];
        let target = other_state(self.design.cells()[cell], materials, rng);
        genome.points.push(self.point_for(cell, target, scene)?);
        Some((cell, target))
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
