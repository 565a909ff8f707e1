//! Diversity of the islands, measured after every epoch so a run shows whether its islands keep
//! apart or converge on one design (`diversity.csv` in the run's folder, and the log).
//!
//! The measure is [`genome_distance`] (the symmetric Chamfer distance between point positions, in
//! normalized workspace units): within an island, the mean over all pairs of individuals; between
//! islands, the distance from each island's best to the run's best. Measuring reads the islands
//! and draws no random numbers, so it never changes a run.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

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

/// Measures every island against the run's best individual (the fittest of all islands, the
/// lowest island on a tie).
pub fn measure(islands: &[Island]) -> Vec<IslandDiversity> {
    let Some(first) = islands.first() else {
        return Vec::new();
    };
    let mut run_best = first.best();
    for island in &islands[1..] {
        if island.best().outcome.is_fitter_than(&run_best.outcome) {
            run_best = island.best();
        }
    }
    islands
        .iter()
        .map(|island| IslandDiversity {
            island: island.id.0,
            mean_pairwise: mean_pairwise_distance(island),
            best_to_run_best: genome_distance(&island.best().genome, &run_best.genome),
            step_scale: island.step_scale(),
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
            "epoch,evaluations,island,mean_pairwise_distance,best_to_run_best,step_scale"
        )?;
        file.flush()?;
        Ok(Self { file })
    }

    /// Measures the islands after `epoch`, logs and writes one row per island.
    pub fn record(
        &mut self,
        epoch: usize,
        evaluations: u64,
        islands: &[Island],
    ) -> std::io::Result<()> {
        for d in measure(islands) {
            info!(
                epoch,
                island = d.island,
                mean_pairwise = d.mean_pairwise,
                best_to_run_best = d.best_to_run_best,
                step_scale = d.step_scale,
                "diversity"
            );
            writeln!(
                self.file,
                "{epoch},{evaluations},{},{:.6},{:.6},{}",
                d.island, d.mean_pairwise, d.best_to_run_best, d.step_scale
            )?;
        }
        self.file.flush()
    }
}
