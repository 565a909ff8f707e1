//! The shared climb alone, from one design, under different ways of adding up its nudges (issue
//! 13, session 37; figures in docs/evolution.md).
//!
//! `cargo bench -p amorph-coordinator --bench climb -- <design.json> <config.toml> <epochs>
//! <nudges> <seeds> <combinations>,<rebase>[,<K>,<R>] [...]`: for each setting (`1,0` is the
//! session-13 rule: one combination of every improving nudge, on the design they started from;
//! `K`, `R` make it a race of K climbs for R epochs, the best one going on; a last `,residuals`
//! picks the nudges by the residual model, `local_search.combine_by`, and `,least_squares:R` takes
//! its least-squares step with `reach` R) and each seed
//! of the comma-separated list, an island holding only the design in `design.json` (a
//! `best_genome.json` or a test fixture: genome and resolution) breeds `nudges` nudges an epoch
//! with the `[search.local_search]` keys of `config.toml` (`fraction` 1, `combine` on) and keeps
//! the fittest, as the run's climb does in the island that holds the best. Prints, per setting
//! and seed, the figure (RMS error for a beam) every ten epochs and at the end, the evaluations spent, and how
//! often a combined design held the best at an epoch's end. The
//! same arguments give the same lines: the island's stream is the seed, and every child is
//! evaluated whatever the number of threads.

#[path = "common/design.rs"]
mod design;

use std::sync::Arc;

use amorph::task::Outcome;
use amorph::voxel::GridDims;
use amorph_coordinator::ids::{IslandId, TaskId};
use amorph_coordinator::search::{Breeding, CombineBy, Individual, Island};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn main() {
    let args = design::arguments(
        6,
        "climb <design.json> <config.toml> <epochs> <nudges> <seed,seed,...> <combinations>,<rebase>...",
    );
    let (genome, dims, config) = design::load(&args[0], &args[1]);
    let scene = Arc::new(config.raw.scene.clone());
    let epochs: usize = args[2].parse().expect("epochs");
    let nudges: usize = args[3].parse().expect("nudges");
    let seeds: Vec<u64> = (args[4].split(','))
        .map(|s| s.parse().expect("a seed"))
        .collect();
    let figure = |o: &Outcome| scene.figure(o).unwrap_or(f64::NAN);
    let start = scene.evaluate(&genome, dims);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    for setting in &args[5..] {
        // A last word `residuals` picks the nudges by the residual model; `least_squares:R`
        // takes its least-squares step, each coefficient within R.
        let (numbers, by, reach) = if let Some(numbers) = setting.strip_suffix(",residuals") {
            (numbers, CombineBy::Residuals, 1.0)
        } else if let Some((numbers, reach)) = setting.split_once(",least_squares:") {
            (
                numbers,
                CombineBy::LeastSquares,
                reach.parse().expect("a reach"),
            )
        } else {
            (setting.as_str(), CombineBy::Fitness, 1.0)
        };
        let v: Vec<usize> = (numbers.split(','))
            .map(|s| s.parse().expect("a number"))
            .collect();
        let mut variation = config.raw.search.variation();
        let local = &mut variation.local_search;
        (local.fraction, local.combine, local.shared) = (1.0, true, false);
        (local.combinations, local.rebase) = (v[0], v[1] != 0);
        (local.combine_by, local.reach) = (by, reach);
        variation.validate().expect("a valid setting");
        let combining = variation.local_search.combining(scene.limits());
        let breeding = Breeding {
            mutation: config.raw.search.mutation.clone(),
            variation,
            scene: scene.clone(),
        };
        // A race (`K`, `R` after the two keys): K climbs from the design, on streams of their own,
        // for R epochs; the one with the best design goes on alone. Its evaluations count all K.
        let (racers, race_epochs) = (
            v.get(2).copied().unwrap_or(1),
            v.get(3).copied().unwrap_or(0),
        );
        for &seed in &seeds {
            let climb = |k: u64| Climb {
                island: Island::from_evaluated(
                    IslandId(0),
                    ChaCha8Rng::seed_from_u64(seed + 1000 * k),
                    vec![Individual {
                        genome: genome.clone(),
                        outcome: start.clone(),
                        task: TaskId(0),
                    }],
                ),
                task: 0,
                offered: 0,
                won: 0,
            };
            let mut line = format!("{setting} seed {seed}: {:.4}", figure(&start));
            let mut raced = 0;
            let mut leader = climb(0);
            if racers > 1 {
                let mut field: Vec<Climb> = (0..racers as u64).map(climb).collect();
                for racer in &mut field {
                    for _ in 0..race_epochs {
                        racer.epoch(&breeding, &scene, dims, nudges, threads, combining);
                    }
                    raced += racer.task;
                }
                leader = (field.into_iter())
                    .reduce(|a, b| {
                        let (x, y) = (&a.island.best().outcome, &b.island.best().outcome);
                        if y.is_fitter_than(x) { b } else { a }
                    })
                    .expect("racers");
                raced -= leader.task;
            }
            let first = if racers > 1 { race_epochs + 1 } else { 1 };
            for epoch in first..=epochs {
                leader.epoch(&breeding, &scene, dims, nudges, threads, combining);
                if epoch.is_multiple_of(10) {
                    line += &format!(" {:.4}", figure(&leader.island.best().outcome));
                }
            }
            if !epochs.is_multiple_of(10) {
                line += &format!(" {:.4}", figure(&leader.island.best().outcome));
            }
            println!(
                "{line} ({} evaluations; {} combined designs offered, one held the best after {} epochs)",
                leader.task + raced,
                leader.offered,
                leader.won
            );
        }
    }
}

/// One climb: an island holding only the climb's best, and what it has spent.
struct Climb {
    island: Island,
    task: u64,
    offered: usize,
    won: usize,
}

impl Climb {
    /// One epoch of `nudges` children, evaluated and applied.
    fn epoch(
        &mut self,
        breeding: &Breeding,
        scene: &amorph::task::Scene,
        dims: GridDims,
        nudges: usize,
        threads: usize,
        combining: Option<amorph_coordinator::search::Combining>,
    ) {
        let children = self.island.breed(nudges, breeding, dims, None);
        let outcomes = evaluate(scene, &children, dims, threads);
        let combined: Vec<u64> = (children.iter().enumerate())
            .filter(|(_, c)| c.combined)
            .map(|(k, _)| self.task + 1 + k as u64)
            .collect();
        let outcomes = (outcomes.into_iter())
            .map(|o| {
                self.task += 1;
                (TaskId(self.task), o)
            })
            .collect();
        self.island.apply(children, outcomes, combining);
        self.offered += combined.len();
        self.won += usize::from(combined.contains(&self.island.best().task.0));
    }
}

/// Every child's outcome, in child order, on `threads` threads.
fn evaluate(
    scene: &amorph::task::Scene,
    children: &[amorph_coordinator::search::Child],
    dims: GridDims,
    threads: usize,
) -> Vec<Outcome> {
    let chunk = children.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let handles: Vec<_> = (children.chunks(chunk))
            .map(|part| {
                s.spawn(move || {
                    (part.iter())
                        .map(|c| scene.evaluate(&c.genome, dims))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        (handles.into_iter())
            .flat_map(|h| h.join().expect("an evaluation thread"))
            .collect()
    })
}
