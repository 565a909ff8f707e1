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

use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::voxel::{GridDims, VoxelGrid};
use tracing::info;

use super::island::{Individual, Island};
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

/// The fittest individual of all islands, the lowest island on a tie.
fn run_best(islands: &[Island]) -> Option<&Individual> {
    let mut run_best = islands.first()?.best();
    for island in &islands[1..] {
        if island.best().outcome.is_fitter_than(&run_best.outcome) {
            run_best = island.best();
        }
    }
    Some(run_best)
}

/// Measures every island against the run's best individual (the fittest of all islands, the
/// lowest island on a tie); designs are made by `scene` at `dims`. Every pair afresh: the
/// reference for [`DiversityLog`]'s incremental measurement.
pub fn measure(islands: &[Island], scene: &Scene, dims: GridDims) -> Vec<IslandDiversity> {
    measure_with(islands, scene, dims, |_, island, run_best_design| {
        let designs: Vec<VoxelGrid> = island
            .population
            .iter()
            .map(|ind| scene.design(&ind.genome, dims))
            .collect();
        (
            mean_pairwise_distance(island),
            mean_pairwise_design_distance(&designs),
            design_distance(&designs[island.best_index()], run_best_design),
        )
    })
}

/// The rows of [`measure`], with each island's two pairwise means and its best's design distance
/// to the run's best (given the run best's design) from `per_island(k, island, run_best_design)`.
fn measure_with(
    islands: &[Island],
    scene: &Scene,
    dims: GridDims,
    mut per_island: impl FnMut(usize, &Island, &VoxelGrid) -> (f64, f64, f64),
) -> Vec<IslandDiversity> {
    let Some(run_best) = run_best(islands) else {
        return Vec::new();
    };
    let run_best_design = scene.design(&run_best.genome, dims);
    islands
        .iter()
        .enumerate()
        .map(|(k, island)| {
            let (mean_pairwise, design_pairwise, design_to_run_best) =
                per_island(k, island, &run_best_design);
            IslandDiversity {
                island: island.id.0,
                mean_pairwise,
                best_to_run_best: genome_distance(&island.best().genome, &run_best.genome),
                design_pairwise,
                design_to_run_best,
            }
        })
        .collect()
}

/// One island's last measurement: its individuals' genomes and designs and every pair's two
/// distances, so that an epoch recomputes only the pairs of the slots whose genome changed. With a
/// few children per island and epoch most of a population is unchanged, and measuring all pairs
/// afresh made the coordinator's epoch several times longer than its evaluations at 16 islands
/// (docs/explanation/search.md). The sums are taken over the same pairs in the same order as
/// [`measure`], so the numbers are the same bits.
#[derive(Debug, Default)]
struct IslandCache {
    dims: Option<GridDims>,
    genomes: Vec<Genome>,
    designs: Vec<VoxelGrid>,
    /// Distances of the pair (i, j), i < j, at `i * n + j`.
    genome_pairs: Vec<f64>,
    design_pairs: Vec<f64>,
}

impl IslandCache {
    /// Brings the cache up to `island` at `dims`; returns the island's two pairwise means.
    fn update(&mut self, island: &Island, scene: &Scene, dims: GridDims) -> (f64, f64) {
        let pop = &island.population;
        let n = pop.len();
        let fresh = self.dims != Some(dims) || self.genomes.len() != n;
        if fresh {
            self.dims = Some(dims);
            self.genomes = pop.iter().map(|ind| ind.genome.clone()).collect();
            self.designs = pop
                .iter()
                .map(|ind| scene.design(&ind.genome, dims))
                .collect();
            self.genome_pairs = vec![0.0; n * n];
            self.design_pairs = vec![0.0; n * n];
        }
        let changed: Vec<bool> = pop
            .iter()
            .zip(&mut self.genomes)
            .zip(&mut self.designs)
            .map(|((ind, genome), design)| {
                if fresh {
                    return true;
                }
                if *genome == ind.genome {
                    return false;
                }
                *genome = ind.genome.clone();
                *design = scene.design(genome, dims);
                true
            })
            .collect();
        let (mut genome_total, mut design_total) = (0.0, 0.0);
        for i in 0..n {
            for j in i + 1..n {
                if changed[i] || changed[j] {
                    self.genome_pairs[i * n + j] =
                        genome_distance(&self.genomes[i], &self.genomes[j]);
                    self.design_pairs[i * n + j] =
                        design_distance(&self.designs[i], &self.designs[j]);
                }
                genome_total += self.genome_pairs[i * n + j];
                design_total += self.design_pairs[i * n + j];
            }
        }
        let pairs = n * n.saturating_sub(1) / 2;
        if pairs == 0 {
            (0.0, 0.0)
        } else {
            (genome_total / pairs as f64, design_total / pairs as f64)
        }
    }
}

/// `diversity.csv`: one row per island per epoch, written as the run goes.
#[derive(Debug)]
pub struct DiversityLog {
    file: BufWriter<File>,
    cache: Vec<IslandCache>,
}

impl DiversityLog {
    /// Creates (or, for a resumed run that replays from the start, recreates) the file.
    pub fn create(run_dir: &Path) -> std::io::Result<Self> {
        let mut file = BufWriter::new(File::create(run_dir.join("diversity.csv"))?);
        writeln!(
            file,
            "epoch,evaluations,island,mean_pairwise_distance,best_to_run_best,design_pairwise,design_to_run_best"
        )?;
        file.flush()?;
        Ok(Self {
            file,
            cache: Vec::new(),
        })
    }

    /// [`measure`], recomputing only what changed since the last call.
    fn measure(
        &mut self,
        islands: &[Island],
        scene: &Scene,
        dims: GridDims,
    ) -> Vec<IslandDiversity> {
        self.cache.resize_with(islands.len(), IslandCache::default);
        let cache = &mut self.cache;
        measure_with(islands, scene, dims, |k, island, run_best_design| {
            let (mean_pairwise, design_pairwise) = cache[k].update(island, scene, dims);
            let best_design = &cache[k].designs[island.best_index()];
            (
                mean_pairwise,
                design_pairwise,
                design_distance(best_design, run_best_design),
            )
        })
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
        for d in self.measure(islands, scene, dims) {
            info!(
                epoch,
                island = d.island,
                mean_pairwise = d.mean_pairwise,
                best_to_run_best = d.best_to_run_best,
                design_pairwise = d.design_pairwise,
                design_to_run_best = d.design_to_run_best,
                "diversity"
            );
            writeln!(
                self.file,
                "{epoch},{evaluations},{},{:.6},{:.6},{:.6},{:.6}",
                d.island,
                d.mean_pairwise,
                d.best_to_run_best,
                d.design_pairwise,
                d.design_to_run_best,
            )?;
        }
        self.file.flush()
    }
}

#[cfg(test)]
mod tests;
