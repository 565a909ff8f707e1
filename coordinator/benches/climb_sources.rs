//! Where a run's improvements came from, read from its store (issue 13, sessions 38–39; figures in
//! docs/evolution.md).
//!
//! `cargo bench -p amorph-coordinator --bench climb_sources -- [--epochs] <run.sqlite>...`: for
//! each store and each resolution level, every child is named by its shape against the run's best
//! at the start of its epoch (`search::step_kind`: copy, one point moved, one point inserted,
//! several changes combined, or other, which is crossover and mutation), and counted: how many
//! children of each kind, how many beat that best, and in how many epochs the new best was one.
//! A combination is built on the design the previous epoch's nudges came from, so a child that
//! is other against the current best is read again against the previous epoch's best. Also the
//! best's figure and point count at the level's first and last epoch, and at a switch whether the
//! new level starts from the last best of the level before (the climb's) or from another design
//! of the re-evaluated populations, with that best's own figure at the new level. With `--epochs`, one line
//! per epoch: the best's figure and points, the improving children by kind, the new best's kind.
//! The store is only read; the same store gives the same lines.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph_coordinator::RunConfig;
use amorph_coordinator::search::{StepKind, step_kind};
use rusqlite::{Connection, OpenFlags};

fn main() {
    let args: Vec<String> = (std::env::args().skip(1))
        .filter(|a| a != "--bench")
        .collect();
    let per_epoch = args.iter().any(|a| a == "--epochs");
    let stores: Vec<&String> = args.iter().filter(|a| *a != "--epochs").collect();
    if stores.is_empty() {
        eprintln!("usage: climb_sources [--epochs] <run.sqlite>...");
        std::process::exit(2);
    }
    for path in stores {
        match Run::read(Path::new(path)) {
            Ok(run) => run.report(path, per_epoch),
            Err(e) => {
                eprintln!("climb_sources: {path}: {e}");
                std::process::exit(1);
            }
        }
    }
}

/// One stored evaluation.
struct Row {
    epoch: usize,
    purpose: String,
    resolution: String,
    genome: Genome,
    outcome: Outcome,
}

/// What a report needs of a store: its scene, its evaluations and the populations after each epoch.
struct Run {
    scene: Scene,
    rows: BTreeMap<u64, Row>,
    /// Task ids of every island's members after each epoch (islands flattened).
    populations: BTreeMap<usize, Vec<u64>>,
    /// Task ids of the evaluations stored under each epoch.
    by_epoch: BTreeMap<usize, Vec<u64>>,
}

impl Run {
    fn read(path: &Path) -> Result<Self, String> {
        let c = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY)
            .map_err(|e| e.to_string())?;
        let config: String = c
            .query_row("SELECT value FROM run WHERE key = 'config'", [], |r| {
                r.get(0)
            })
            .map_err(|e| format!("table run, key config: {e}"))?;
        let scene = (RunConfig::parse(&config, path).map_err(|e| e.to_string())?)
            .raw
            .scene;
        let mut rows = BTreeMap::new();
        let mut stmt = c
            .prepare("SELECT task_id, epoch, purpose, resolution, genome, outcome FROM evaluation")
            .map_err(|e| e.to_string())?;
        let read = stmt
            .query_map([], |r| {
                let (id, epoch): (i64, i64) = (r.get(0)?, r.get(1)?);
                let (purpose, resolution, genome, outcome): (String, String, String, String) =
                    (r.get(2)?, r.get(3)?, r.get(4)?, r.get(5)?);
                Ok((id, epoch, purpose, resolution, genome, outcome))
            })
            .map_err(|e| e.to_string())?;
        for row in read {
            let (id, epoch, purpose, resolution, genome, outcome) =
                row.map_err(|e| e.to_string())?;
            let bad = |what: &str, e: &dyn std::fmt::Display| {
                format!("table evaluation, task_id {id}: {what}: {e}")
            };
            let row = Row {
                epoch: usize::try_from(epoch).map_err(|e| bad("epoch", &e))?,
                purpose,
                resolution,
                genome: serde_json::from_str(&genome).map_err(|e| bad("genome", &e))?,
                outcome: serde_json::from_str(&outcome).map_err(|e| bad("outcome", &e))?,
            };
            rows.insert(u64::try_from(id).map_err(|e| bad("task_id", &e))?, row);
        }
        let mut populations: BTreeMap<usize, Vec<u64>> = BTreeMap::new();
        let mut stmt = c
            .prepare("SELECT epoch, task_id FROM population ORDER BY epoch, island, slot")
            .map_err(|e| e.to_string())?;
        let read = stmt
            .query_map([], |r| Ok((r.get::<_, i64>(0)?, r.get::<_, i64>(1)?)))
            .map_err(|e| e.to_string())?;
        for row in read {
            let (epoch, task) = row.map_err(|e| e.to_string())?;
            let (Ok(epoch), Ok(task)) = (usize::try_from(epoch), u64::try_from(task)) else {
                return Err(format!(
                    "table population: row ({epoch}, {task}) is negative"
                ));
            };
            if !rows.contains_key(&task) {
                return Err(format!(
                    "table population, epoch {epoch}: task {task} has no evaluation"
                ));
            }
            populations.entry(epoch).or_default().push(task);
        }
        let mut by_epoch: BTreeMap<usize, Vec<u64>> = BTreeMap::new();
        for (&id, row) in &rows {
            by_epoch.entry(row.epoch).or_default().push(id);
        }
        Ok(Self {
            scene,
            rows,
            populations,
            by_epoch,
        })
    }

    /// The fittest member after `epoch`, as judged at `resolution`: a member evaluated at another
    /// resolution (the last coarse population, before the switch) is judged by its evaluation at
    /// this one, the switch's re-evaluation of the same genome.
    fn best_after(&self, epoch: usize, resolution: &str) -> Option<(&Genome, &Outcome)> {
        let stored = self.by_epoch.get(&epoch).map_or(&[][..], Vec::as_slice);
        // The initial population is not stored as a population: its evaluations are.
        let initial: Vec<u64> = (stored.iter().copied())
            .filter(|t| self.rows[t].purpose == "initial")
            .collect();
        let members = match self.populations.get(&epoch) {
            Some(members) => members.as_slice(),
            None if !initial.is_empty() => initial.as_slice(),
            None => return None,
        };
        (members.iter())
            .filter_map(|t| {
                let row = &self.rows[t];
                if row.resolution == resolution {
                    return Some((&row.genome, &row.outcome));
                }
                (stored.iter().map(|t| &self.rows[t]))
                    .find(|r| r.resolution == resolution && r.genome == row.genome)
                    .map(|r| (&row.genome, &r.outcome))
            })
            .reduce(|a, b| if b.1.is_fitter_than(a.1) { b } else { a })
    }

    /// An evaluation of exactly `genome` at `resolution` (a check or a re-evaluation), if any.
    fn outcome_at(&self, genome: &Genome, resolution: &str) -> Option<&Outcome> {
        (self.rows.values())
            .find(|r| r.resolution == resolution && r.genome == *genome)
            .map(|r| &r.outcome)
    }

    fn report(&self, path: &str, per_epoch: bool) {
        let figure = |o: &Outcome| self.scene.figure(o).unwrap_or(f64::NAN);
        // Children by level, in the order the levels came.
        let mut levels: Vec<(String, BTreeMap<usize, Vec<u64>>)> = Vec::new();
        for (&id, row) in self.rows.iter().filter(|(_, r)| r.purpose == "child") {
            if levels.last().is_none_or(|(r, _)| *r != row.resolution) {
                levels.push((row.resolution.clone(), BTreeMap::new()));
            }
            let level = &mut levels.last_mut().expect("a level").1;
            level.entry(row.epoch).or_default().push(id);
        }
        println!("{path}");
        // The last best of the level before, to say whether the switch handed it on.
        let mut handed: Option<&Genome> = None;
        for (resolution, epochs) in &levels {
            let previous_best = handed;
            let mut start: Option<&Genome> = None;
            let mut tally: BTreeMap<StepKind, [usize; 3]> = BTreeMap::new();
            let (mut first, mut last) = (None, None);
            // Each epoch's best is read up to three times (as the best after it, and as the
            // base of the next two epochs): found once.
            let mut bests = HashMap::new();
            let mut best_after = |e: usize| {
                *bests
                    .entry(e)
                    .or_insert_with(|| self.best_after(e, resolution))
            };
            for (&epoch, children) in epochs {
                let Some((base, base_outcome)) = best_after(epoch - 1) else {
                    continue;
                };
                let previous = (epoch >= 2).then(|| best_after(epoch - 2)).flatten();
                let mut improving: BTreeMap<StepKind, usize> = BTreeMap::new();
                let mut fittest: Option<(StepKind, &Outcome)> = None;
                for id in children {
                    let child = &self.rows[id];
                    let mut kind = step_kind(base, &child.genome);
                    if kind == StepKind::Other
                        && let Some((earlier, _)) = previous
                        && step_kind(earlier, &child.genome) == StepKind::Combined
                    {
                        kind = StepKind::Combined;
                    }
                    let t = tally.entry(kind).or_default();
                    t[0] += 1;
                    if child.outcome.is_fitter_than(base_outcome) {
                        t[1] += 1;
                        *improving.entry(kind).or_default() += 1;
                        if fittest.is_none_or(|(_, o)| child.outcome.is_fitter_than(o)) {
                            fittest = Some((kind, &child.outcome));
                        }
                    }
                }
                if let Some((kind, _)) = fittest {
                    tally.entry(kind).or_default()[2] += 1;
                }
                first.get_or_insert((epoch, figure(base_outcome), base.points.len()));
                start.get_or_insert(base);
                if let Some((genome, outcome)) = best_after(epoch) {
                    last = Some((epoch, figure(outcome), genome.points.len()));
                    handed = Some(genome);
                }
                if per_epoch {
                    let kinds: Vec<String> = (improving.iter())
                        .map(|(k, n)| format!("{} {n}", k.name()))
                        .collect();
                    println!(
                        "  {resolution} epoch {epoch}: best {:.4}, {} points; {} children beat it ({}); new best: {}",
                        figure(base_outcome),
                        base.points.len(),
                        improving.values().sum::<usize>(),
                        kinds.join(", "),
                        fittest.map_or("none", |(k, _)| k.name()),
                    );
                }
            }
            let (Some(first), Some(last)) = (first, last) else {
                continue;
            };
            if let (Some(previous), Some(start)) = (previous_best, start) {
                let here = self
                    .outcome_at(previous, resolution)
                    .map_or("not evaluated here".to_string(), |o| {
                        format!("{:.4} here", figure(o))
                    });
                let kind = step_kind(previous, start);
                println!(
                    "  switch: the level before ended on a best of {} points ({here}); this level starts from {}",
                    previous.points.len(),
                    if kind == StepKind::Copy {
                        "that design".to_string()
                    } else {
                        format!("another design ({} against it)", kind.name())
                    },
                );
            }
            println!(
                "  {resolution}: epochs {}-{}, best {:.4} -> {:.4}, best's points {} -> {} ({:+.2} an epoch)",
                first.0,
                last.0,
                first.1,
                last.1,
                first.2,
                last.2,
                (last.2 as f64 - first.2 as f64) / (last.0 + 1 - first.0) as f64,
            );
            println!("    kind       children  beat the best  epochs it set the new best");
            for kind in StepKind::ALL {
                let t = tally.get(&kind).copied().unwrap_or_default();
                println!(
                    "    {:<10} {:>8}  {:>13}  {:>6}",
                    kind.name(),
                    t[0],
                    t[1],
                    t[2]
                );
            }
        }
    }
}
