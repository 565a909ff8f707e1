//! Wall time against workers, simulated from a finished run (issue 13; figures in
//! docs/evolution.md). Reads a run store, replays its epochs on W workers (`run::schedule`), and
//! checks the model against runs of the same config and seed made with other worker counts.
//!
//! `cargo bench -p amorph-coordinator --bench wall_model -- <run.sqlite> [--workers 1,2,16,256]
//! [--fitness F] [--overlap on|off] [--check <other run.sqlite>]...`
//!
//! `--overlap` simulates the run with its finest-level checks sent out with the next epoch's
//! children or alone (default: as the run did, which its stored config says); the coordinator's
//! time is always taken from the run as it ran.
//!
//! `--fitness` adds the wall time to the first epoch whose best reaches F. A beam's fitness is
//! minus the sum of its stations' squared errors, −N·(RMS/100)² for N stations: the paper's
//! 0.10 % is −1.9e-5 on the 19 stations of 6×20×6 and −3.9e-5 on the 39 of 12×40×12.

use std::path::PathBuf;

use amorph_coordinator::run::schedule::{
    EpochTimes, RecordedRun, first_reaching, overheads, simulated_wall,
};
use amorph_coordinator::store::RunStore;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let mut store = None;
    let mut workers = vec![1, 2, 4, 8, 16, 32, 64, 256];
    let mut fitness = None;
    let mut checks = Vec::new();
    let mut overlap = None;
    let mut i = 0;
    while i < args.len() {
        let value = args.get(i + 1);
        match (args[i].as_str(), value) {
            ("--workers", Some(v)) => {
                workers = v
                    .split(',')
                    .map(|w| w.parse().expect("--workers: counts"))
                    .collect();
                i += 1;
            }
            ("--fitness", Some(v)) => {
                fitness = Some(v.parse::<f64>().expect("--fitness: a number"));
                i += 1;
            }
            ("--overlap", Some(v)) => {
                overlap = Some(match v.as_str() {
                    "on" => true,
                    "off" => false,
                    _ => {
                        eprintln!("wall_model: --overlap takes on or off, not {v}");
                        std::process::exit(2);
                    }
                });
                i += 1;
            }
            ("--check", Some(v)) => {
                checks.push(PathBuf::from(v));
                i += 1;
            }
            (path, _) if store.is_none() && !path.starts_with("--") => {
                store = Some(PathBuf::from(path));
            }
            (other, _) => {
                eprintln!("wall_model: unexpected argument {other}");
                std::process::exit(2);
            }
        }
        i += 1;
    }
    let Some(store) = store else {
        eprintln!(
            "usage: wall_model <run.sqlite> [--workers 1,2,16] [--fitness F] [--overlap on|off] [--check other.sqlite]..."
        );
        std::process::exit(2);
    };
    let load = |path: &PathBuf| -> RecordedRun {
        RunStore::peek_recorded_run(path).unwrap_or_else(|e| {
            eprintln!("wall_model: {e}");
            std::process::exit(1)
        })
    };
    let recorded = load(&store);
    let measured = recorded.workers;
    let overhead = overheads(&recorded.epochs(recorded.overlapped), measured);
    let simulate_overlap = overlap.unwrap_or(recorded.overlapped);
    let epochs = recorded.epochs(simulate_overlap);
    let measured_wall = epochs.last().map_or(0.0, |e| e.wall_seconds);
    let evaluations = epochs.last().map_or(0, |e| e.evaluations);
    let widest = epochs
        .iter()
        .flat_map(|e| e.batches.iter().map(Vec::len))
        .max()
        .unwrap_or(0);
    println!(
        "{}: {} epochs, {evaluations} evaluations, widest batch {widest}, {measured} worker(s), {measured_wall:.1} s measured, coordinator {:.1} s, checks {} as run, simulated {}",
        store.display(),
        epochs.len(),
        overhead.iter().sum::<f64>(),
        if recorded.overlapped {
            "overlapped"
        } else {
            "alone"
        },
        if simulate_overlap {
            "overlapped"
        } else {
            "alone"
        },
    );
    let target = fitness.and_then(|f| first_reaching(&epochs, f));
    if let Some(f) = fitness {
        match target {
            Some(t) => println!(
                "fitness {f} first reached in epoch {} ({} evaluations)",
                epochs[t].epoch, epochs[t].evaluations
            ),
            None => println!("fitness {f} not reached in this run"),
        }
    }
    println!("| workers | simulated wall, s | speed-up | to the fitness, s |");
    println!("|---|---|---|---|");
    let one = simulated_wall(&epochs, &overhead, 1);
    for &w in &workers {
        let wall = simulated_wall(&epochs, &overhead, w);
        let total = wall.last().copied().unwrap_or(0.0);
        let to_target = target.map_or("–".to_owned(), |t| format!("{:.1}", wall[t]));
        println!(
            "| {w} | {total:.1} | {:.2} | {to_target} |",
            one.last().copied().unwrap_or(0.0) / total.max(1e-12)
        );
    }
    for check in &checks {
        let other_run = load(check);
        let other_workers = other_run.workers;
        // Both runs batched the way the other one scheduled its checks.
        let other = other_run.epochs(other_run.overlapped);
        let as_other = recorded.epochs(other_run.overlapped);
        if !same_schedule(&as_other, &other) {
            eprintln!(
                "wall_model: {} is not the same run (epochs, evaluation counts or batch sizes differ)",
                check.display()
            );
            std::process::exit(1);
        }
        let predicted = simulated_wall(&as_other, &overhead, other_workers)
            .last()
            .copied()
            .unwrap_or(0.0);
        let actual = other.last().map_or(0.0, |e| e.wall_seconds);
        println!(
            "check {}: {other_workers} worker(s), measured {actual:.1} s, simulated {predicted:.1} s ({:+.1} %)",
            check.display(),
            100.0 * (predicted - actual) / actual
        );
    }
}

/// Same config and seed: the same epochs with the same batch sizes.
fn same_schedule(a: &[EpochTimes], b: &[EpochTimes]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.epoch == y.epoch
                && x.evaluations == y.evaluations
                && x.batches
                    .iter()
                    .map(Vec::len)
                    .eq(y.batches.iter().map(Vec::len))
        })
}
