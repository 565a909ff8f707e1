//! Diversity of the islands, measured after every epoch so a run shows whether its islands keep
//! apart or converge on one design (`diversity.csv` in the run's folder, and the log).
//!
//! Two measures, because genomes can differ while their designs agree (points outside the
//! workspace, carved away or cut off from the clamp make no voxels): the genome distance
//! ([`genome_distance`], the symmetric Chamfer distance between point positions, in normalized
//! workspace units) and the design distance (the share of voxels whose material, or emptiness,
//! differs at the run's current resolution). Within an island: the mean over all pairs of
//! individuals; between islands: each island's best against the run's best. Measuring reads the
//! islands and draws no random numbers, so it never changes a run.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use amorph::task::Scene;
use amorph::voxel::{GridDims, VoxelGrid};
use tracing::info;

use super::island::Island;
use super::migration::genome_distance;

/// What an island looks like after an epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct IslandDiversity {
    pub island: u32,
    /// Mean genome distance over all pairs of the island's individuals (0 for one individual).
    pub mean_pairwise: f64,
    /// Genome distance from the island's best to the run's best (0 on the island holding it).
    pub best_to_run_best: f64,
    /// Mean design distance over all pairs of the island's individuals.
    pub design_pairwise: f64,
    /// Design distance from the island's best to the run's best.
    pub design_to_run_best: f64,
    /// The island's mutation step as a multiple of the configured one.
    pub step_scale: f64,
}

/// The mean genome distance over all unordered pairs of an island's individuals.
pub fn mean_pairwise_distance(island: &Island) -> f64 {
    let pop = &island.population;
    let mut total = 0.0;
    let mut pairs = 0usize;
    for (i, a) in pop.iter().enumerate() {
        for b in &pop[i + 1..] {
            total += genome_distance(&a.genome, &b.genome);
            pairs += 1;
        }
    }
    if pairs == 0 {
        0.0
    } else {
        total / pairs as f64
    }
}

/// The share of cells whose content (empty or which material) differs between two designs of the
/// same resolution.
pub fn design_distance(a: &VoxelGrid, b: &VoxelGrid) -> f64 {
    let (a, b) = (a.cells(), b.cells());
    if a.is_empty() {
        return 0.0;
    }
    let differ = a.iter().zip(b).filter(|(x, y)| x != y).count();
    differ as f64 / a.len() as f64
}

fn mean_pairwise_design_distance(designs: &[VoxelGrid]) -> f64 {
    let mut total = 0.0;
    let mut pairs = 0usize;
    for (i, a) in designs.iter().enumerate() {
        for b in &designs[i + 1..] {
            total += design_distance(a, b);
            pairs += 1;
        }
    }
    if pairs == 0 {
        0.0
    } else {
        total / pairs as f64
    }
}

/// Measures every island against the run's best individual (the fittest of all islands, the
/// lowest island on a tie); designs are made by `scene` at `dims`.
pub fn measure(islands: &[Island], scene: &Scene, dims: GridDims) -> Vec<IslandDiversity> {
    let Some(first) = islands.first() else {
        return Vec::new();
    };
    let mut run_best = first.best();
    for island in &islands[1..] {
        if island.best().outcome.is_fitter_than(&run_best.outcome) {
            run_best = island.best();
        }
    }
    let run_best_design = scene.design(&run_best.genome, dims);
    islands
        .iter()
        .map(|island| {
            let designs: Vec<VoxelGrid> = island
                .population
                .iter()
                .map(|ind| scene.design(&ind.genome, dims))
                .collect();
            IslandDiversity {
                island: island.id.0,
                mean_pairwise: mean_pairwise_distance(island),
                best_to_run_best: genome_distance(&island.best().genome, &run_best.genome),
                design_pairwise: mean_pairwise_design_distance(&designs),
                design_to_run_best: design_distance(
                    &designs[island.best_index()],
                    &run_best_design,
                ),
                step_scale: island.step_scale(),
            }
        })
        .collect()
}

/// `diversity.csv`: one row per island per epoch, written as the run goes.
#[derive(Debug)]
pub struct DiversityLog {
    file: BufWriter<File>,
}

impl DiversityLog {
    /// Creates (or, for a resumed run that replays from the start, recreates) the file.
    pub fn create(run_dir: &Path) -> std::io::Result<Self> {
        let mut file = BufWriter::new(File::create(run_dir.join("diversity.csv"))?);
        writeln!(
            file,
            "epoch,evaluations,island,mean_pairwise_distance,best_to_run_best,design_pairwise,design_to_run_best,step_scale"
        )?;
        file.flush()?;
        Ok(Self { file })
    }

    /// Measures the islands after `epoch` (designs at `dims`), logs and writes one row per island.
    pub fn record(
        &mut self,
        epoch: usize,
        evaluations: u64,
        islands: &[Island],
        scene: &Scene,
        dims: GridDims,
    ) -> std::io::Result<()> {
        for d in measure(islands, scene, dims) {
            info!(
                epoch,
                island = d.island,
                mean_pairwise = d.mean_pairwise,
                best_to_run_best = d.best_to_run_best,
                design_pairwise = d.design_pairwise,
                design_to_run_best = d.design_to_run_best,
                step_scale = d.step_scale,
                "diversity"
            );
            writeln!(
                self.file,
                "{epoch},{evaluations},{},{:.6},{:.6},{:.6},{:.6},{}",
                d.island,
                d.mean_pairwise,
                d.best_to_run_best,
                d.design_pairwise,
                d.design_to_run_best,
                d.step_scale
            )?;
        }
        self.file.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::fixtures::island;
    use amorph::material::MaterialId;

    #[test]
    fn mean_pairwise_distance_averages_every_pair_once() {
        // One-point genomes at 0.1, 0.2, 0.4: pair distances 0.1, 0.3, 0.2.
        let isl = island(0, &[0.1, 0.2, 0.4], &[-1.0, -2.0, -3.0]);
        assert!((mean_pairwise_distance(&isl) - 0.2).abs() < 1e-15);
        assert_eq!(mean_pairwise_distance(&island(0, &[0.3], &[-1.0])), 0.0);
    }

    #[test]
    fn design_distance_is_the_share_of_differing_cells() {
        let dims = GridDims::new(1, 4, 1);
        let soft = Some(MaterialId(0));
        let hard = Some(MaterialId(1));
        let a = VoxelGrid::from_cells(dims, vec![soft, soft, hard, None]);
        let b = VoxelGrid::from_cells(dims, vec![soft, hard, None, None]);
        assert_eq!(design_distance(&a, &a), 0.0);
        assert_eq!(
            design_distance(&a, &b),
            0.5,
            "a material and an emptiness differ"
        );
        assert_eq!(design_distance(&a, &b), design_distance(&b, &a));
    }
}
