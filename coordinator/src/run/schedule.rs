//! Wall time against workers, simulated from a finished run (issue 13): the same epochs, the same
//! evaluations with the wall time each took, handed to W workers the way the task queue hands
//! them out, plus the coordinator's own time per epoch as measured. It is a model, not a run:
//! what it leaves out (network latency, a worker's start-up, machines of unequal speed) is what a
//! check against a measured run with another number of workers shows.

use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap};

use crate::store::Purpose;

/// One recorded epoch: its batches of evaluations (the wall time of each, in task order) and the
/// run's wall clock and evaluation count when it ended.
#[derive(Clone, Debug, PartialEq)]
pub struct EpochTimes {
    pub epoch: usize,
    /// Batches in the order they ran (a first epoch also holds the initial population's batch).
    pub batches: Vec<Vec<f64>>,
    pub wall_seconds: f64,
    pub evaluations: u64,
    pub best_fitness: Option<f64>,
}

/// What a run store records of a run's timing: its epoch rows (epoch, evaluations, wall clock,
/// best fitness), every evaluation in task order (the epoch it is filed under, why it ran, its
/// wall time), how many distinct workers evaluated, and whether checks at the finest level went
/// out with the next epoch's children (`resolution.overlap_finest_checks`).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedRun {
    pub rows: Vec<(usize, u64, f64, Option<f64>)>,
    pub evaluations: Vec<(usize, Purpose, f64)>,
    pub workers: usize,
    pub overlapped: bool,
}

impl RecordedRun {
    /// The run's epochs with their batches as they run with checks `overlapped` or not. A batch
    /// is a stretch of tasks of one epoch and purpose. Children run on their own epoch's clock;
    /// anything asked for at the end of an epoch (a finest-level check, a switch's re-evaluation;
    /// the initial population before epoch 1) runs on the next row's clock, the last row's if the
    /// run ended first. Overlapped, a check and the next epoch's children that follow it are one
    /// batch (the check handed out first); where the check ended the level its children were
    /// dropped unrecorded, so that check runs alone here.
    pub fn epochs(&self, overlapped: bool) -> Vec<EpochTimes> {
        let mut batches: Vec<(usize, Purpose, Vec<f64>)> = Vec::new();
        for &(epoch, purpose, seconds) in &self.evaluations {
            match batches.last_mut() {
                Some((e, p, b)) if *e == epoch && *p == purpose => b.push(seconds),
                _ => batches.push((epoch, purpose, vec![seconds])),
            }
        }
        let row_of: BTreeMap<usize, usize> = (self.rows.iter().enumerate())
            .map(|(i, r)| (r.0, i))
            .collect();
        let mut times: Vec<EpochTimes> = (self.rows.iter())
            .map(
                |&(epoch, evaluations, wall_seconds, best_fitness)| EpochTimes {
                    epoch,
                    batches: Vec::new(),
                    wall_seconds,
                    evaluations,
                    best_fitness,
                },
            )
            .collect();
        let Some(last) = times.len().checked_sub(1) else {
            return times;
        };
        let mut batches = batches.into_iter().peekable();
        while let Some((epoch, purpose, mut durations)) = batches.next() {
            let runs_in = match purpose {
                Purpose::Child => epoch,
                Purpose::Initial | Purpose::Reevaluation | Purpose::FinestCheck => epoch + 1,
            };
            if overlapped
                && purpose == Purpose::FinestCheck
                && batches
                    .peek()
                    .is_some_and(|(e, p, _)| *p == Purpose::Child && *e == epoch + 1)
            {
                let (_, _, children) = batches.next().expect("peeked");
                durations.extend(children);
            }
            let row = row_of.get(&runs_in).copied().unwrap_or(last);
            times[row].batches.push(durations);
        }
        times
    }
}

/// Time for `workers` to evaluate a batch whose evaluations take `durations` s, handed out in
/// order, each to the worker that becomes free first (the queue's order: the lowest task id to the
/// first worker asking). Ties go to the lowest worker index, so the result is deterministic.
pub fn makespan(durations: &[f64], workers: usize) -> f64 {
    let workers = workers.max(1);
    if workers >= durations.len() {
        return durations.iter().copied().fold(0.0, f64::max);
    }
    // Free times as integer nanoseconds so the heap is ordered without NaN questions.
    let nanos = |s: f64| (s.max(0.0) * 1e9).round() as u64;
    let mut free: BinaryHeap<Reverse<(u64, usize)>> =
        (0..workers).map(|w| Reverse((0, w))).collect();
    let mut end = 0;
    for &d in durations {
        let Reverse((at, w)) = free.pop().expect("at least one worker");
        let done = at + nanos(d);
        end = end.max(done);
        free.push(Reverse((done, w)));
    }
    end as f64 * 1e-9
}

/// The coordinator's time in each epoch: the measured epoch wall time less what its batches take
/// on the `measured_workers` the run had. An epoch's value can be negative, and must stay so: an
/// evaluation is filed under the epoch that asked for it, but a batch asked for at the end of one
/// epoch (the switch's re-evaluation, a finest-level check) runs on the clock of the next row, so
/// per epoch the two do not line up, while over the run they add up. Clipping each epoch at zero
/// kept the surplus and dropped the deficit: on an idle 16-core machine a run simulated on its own
/// worker count came out 9–12 % slower than it ran (docs/evolution.md, session 23).
pub fn overheads(epochs: &[EpochTimes], measured_workers: usize) -> Vec<f64> {
    let mut before = 0.0;
    epochs
        .iter()
        .map(|e| {
            let spent = e.wall_seconds - before;
            before = e.wall_seconds;
            let work: f64 = e
                .batches
                .iter()
                .map(|b| makespan(b, measured_workers))
                .sum();
            spent - work
        })
        .collect()
}

/// The run's wall clock at the end of each epoch had it run on `workers` workers, with the
/// coordinator time `overhead` per epoch.
pub fn simulated_wall(epochs: &[EpochTimes], overhead: &[f64], workers: usize) -> Vec<f64> {
    let mut clock = 0.0;
    epochs
        .iter()
        .zip(overhead)
        .map(|(e, o)| {
            clock += e.batches.iter().map(|b| makespan(b, workers)).sum::<f64>() + o;
            clock
        })
        .collect()
}

/// The first epoch whose best fitness is at least `fitness` (a beam's fitness is −RMS), if any.
pub fn first_reaching(epochs: &[EpochTimes], fitness: f64) -> Option<usize> {
    epochs
        .iter()
        .position(|e| e.best_fitness.is_some_and(|f| f >= fitness))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_worker_takes_the_sum_and_enough_workers_the_longest() {
        let d = [0.3, 1.0, 0.2, 0.5];
        assert!((makespan(&d, 1) - 2.0).abs() < 1e-9);
        assert!((makespan(&d, 4) - 1.0).abs() < 1e-9);
        assert!((makespan(&d, 64) - 1.0).abs() < 1e-9);
        assert_eq!(makespan(&[], 3), 0.0);
    }

    #[test]
    fn tasks_go_to_the_first_free_worker_in_order() {
        // Two workers: 3 on w0, 1 on w1; w1 frees at 1 and takes 1 (ends 2) and then 1 (ends 3),
        // w0 frees at 3 and takes the last 1 (ends 4).
        assert!((makespan(&[3.0, 1.0, 1.0, 1.0, 1.0], 2) - 4.0).abs() < 1e-9);
        // Greedy in order is not optimal: the long task last leaves one worker idle.
        assert!((makespan(&[1.0, 1.0, 2.0], 2) - 3.0).abs() < 1e-9);
    }

    #[test]
    fn simulating_the_measured_worker_count_gives_back_the_measured_clock() {
        let epochs = vec![
            EpochTimes {
                epoch: 1,
                batches: vec![vec![1.0, 2.0, 3.0], vec![1.0, 1.0]],
                wall_seconds: 9.0,
                evaluations: 5,
                best_fitness: Some(-0.02),
            },
            EpochTimes {
                epoch: 2,
                batches: vec![vec![2.0, 2.0]],
                wall_seconds: 13.5,
                evaluations: 7,
                best_fitness: Some(-0.01),
            },
        ];
        let overhead = overheads(&epochs, 1);
        assert!((overhead[0] - 1.0).abs() < 1e-9 && (overhead[1] - 0.5).abs() < 1e-9);
        let same = simulated_wall(&epochs, &overhead, 1);
        assert!((same[0] - 9.0).abs() < 1e-9 && (same[1] - 13.5).abs() < 1e-9);
        // Two workers: [1, 2, 3] takes 4 (the 3 starts when the 1 ends), [1, 1] takes 1, [2, 2]
        // takes 2; each epoch keeps its overhead.
        let two = simulated_wall(&epochs, &overhead, 2);
        assert!((two[0] - 6.0).abs() < 1e-9 && (two[1] - 8.5).abs() < 1e-9);
        assert_eq!(first_reaching(&epochs, -0.015), Some(1));
        assert_eq!(first_reaching(&epochs, -0.001), None);
    }

    #[test]
    fn a_batch_filed_under_an_earlier_epoch_than_its_clock_still_adds_up() {
        // A 3 s batch asked for at the end of epoch 1 (filed there) ran after epoch 1's row was
        // stamped, so epoch 1 measured 1 s for 4 s of filed work and epoch 2 measured 5 s for 2 s.
        // The coordinator spent nothing: the run's 6 s are its work, and simulated on its own
        // worker count it must take 6 s, where clipping epoch 1's −3 s at zero would give 9.
        let epochs = vec![
            EpochTimes {
                epoch: 1,
                batches: vec![vec![1.0], vec![3.0]],
                wall_seconds: 1.0,
                evaluations: 2,
                best_fitness: None,
            },
            EpochTimes {
                epoch: 2,
                batches: vec![vec![1.0, 1.0]],
                wall_seconds: 6.0,
                evaluations: 4,
                best_fitness: None,
            },
        ];
        let overhead = overheads(&epochs, 1);
        assert!(overhead.iter().sum::<f64>().abs() < 1e-9);
        let same = simulated_wall(&epochs, &overhead, 1);
        assert!((same[1] - 6.0).abs() < 1e-9);
        // Two workers: [1] 1, [3] 3, [1, 1] 1, so 5 s of work and no coordinator time left over.
        let two = simulated_wall(&epochs, &overhead, 2);
        assert!((two[1] - 5.0).abs() < 1e-9);
    }

    /// Batches land on the clock they ran on: the initial population and anything asked for at
    /// the end of an epoch on the next row, children on their own. Overlapped, a check and the
    /// next epoch's children are one batch; a check that ended the level (a re-evaluation
    /// follows, its children dropped) runs alone.
    #[test]
    fn batches_run_on_the_row_after_the_epoch_that_asked_for_them() {
        use Purpose::{Child, FinestCheck, Initial, Reevaluation};
        let run = RecordedRun {
            rows: vec![(1, 4, 10.0, None), (2, 7, 20.0, None), (3, 12, 30.0, None)],
            evaluations: vec![
                (0, Initial, 1.0),
                (0, Initial, 1.0),
                (1, Child, 2.0),
                (1, Child, 2.0),
                (1, FinestCheck, 5.0),
                (2, Child, 1.0),
                (2, Child, 1.0),
                (2, FinestCheck, 5.0),
                (2, Reevaluation, 3.0),
                (2, Reevaluation, 3.0),
                (3, Child, 1.0),
                (3, Child, 1.0),
            ],
            workers: 2,
            overlapped: true,
        };
        let batches = |overlapped| -> Vec<Vec<Vec<f64>>> {
            (run.epochs(overlapped).into_iter())
                .map(|e| e.batches)
                .collect()
        };
        let last = vec![vec![5.0], vec![3.0, 3.0], vec![1.0, 1.0]];
        assert_eq!(
            batches(false),
            [
                vec![vec![1.0, 1.0], vec![2.0, 2.0]],
                vec![vec![5.0], vec![1.0, 1.0]],
                last.clone(),
            ]
        );
        assert_eq!(
            batches(true),
            [
                vec![vec![1.0, 1.0], vec![2.0, 2.0]],
                vec![vec![5.0, 1.0, 1.0]],
                last,
            ]
        );
        // On two workers the check alone then its children take 5 + 1 s; beside them, 5 s.
        let work = |overlapped| -> f64 {
            run.epochs(overlapped)[1]
                .batches
                .iter()
                .map(|b| makespan(b, 2))
                .sum()
        };
        assert!((work(false) - 6.0).abs() < 1e-9 && (work(true) - 5.0).abs() < 1e-9);
    }
}
