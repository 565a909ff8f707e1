//! `search.skip_unchanged` drops the children whose design is their dominant parent's
//! before they are evaluated. Such a child scores its parent's bits and so can never replace it:
//! the run must breed, replace, migrate and switch resolution exactly as without
//! the key, epoch by epoch, and spend exactly the dropped children fewer evaluations.

use amorph_coordinator::summary::HistoryRow;
use amorph_coordinator::{RunConfig, RunSummary, StopReason};
use amorph_tests::{
    fingerprint, resume_locally, run_locally, scratch_dir, test_config, thread_count_blind,
};
use std::path::Path;

/// Three islands on two levels with every policy that keeps state across epochs: the shared,
/// combined climb with insertions, migration into the most similar slot, a switch by the stall
/// rule.
fn config(results_dir: &Path, skip: bool, evaluations: u64, target: Option<f64>) -> RunConfig {
    judged(results_dir, skip, evaluations, target, false)
}

/// [`config`], with `on_finest` the coarse level judged on the finest grid: each check there goes
/// out with the next epoch's children, which the switch drops again (and with them the count of
/// copies among them).
fn judged(
    results_dir: &Path,
    skip: bool,
    evaluations: u64,
    target: Option<f64>,
    on_finest: bool,
) -> RunConfig {
    let skip_unchanged = format!("search.skip_unchanged={skip}");
    let budget = format!("budget.evaluations={evaluations}");
    let stall_on_finest = format!("resolution.stall_on_finest={on_finest}");
    let mut sets = vec![
        if skip {
            "name=skipping"
        } else {
            "name=evaluating"
        },
        "seed=5",
        "search.population=8",
        "search.islands=3",
        "search.children_per_epoch=8",
        "search.initial_points=12",
        &skip_unchanged,
        "search.mutation.probability=0.05",
        "search.mutation.step=0.02",
        "search.migration.interval=3",
        "search.migration.topology={ kind = \"ring\" }",
        "search.migration.replacement=most_similar",
        "search.local_search.fraction=0.5",
        "search.local_search.step=0.01",
        "search.local_search.insertion=0.3",
        "search.local_search.shared=true",
        "search.local_search.combine=true",
        &budget,
        "resolution.levels=[[3, 9, 3], [4, 12, 4]]",
        "resolution.stall_epochs=3",
        "resolution.min_improvement=0.2",
        &stall_on_finest,
    ];
    let target = target.map(|t| format!("budget.target_rms_percent={t}"));
    sets.extend(target.as_deref());
    test_config("circular_arc", results_dir, &sets)
}

/// The history both runs must share: every island after every epoch, but for when it ended (the
/// evaluations spent and the wall time).
fn epochs(summary: &RunSummary) -> Vec<HistoryRow> {
    (summary.history.iter())
        .map(|r| HistoryRow {
            evaluations: 0,
            wall_seconds: 0.0,
            ..r.clone()
        })
        .collect()
}

/// The target both runs stop at, so that both stop by it (not by the budget) in the same epoch:
/// an RMS error the run without the key reaches about 35 epochs after its switch to 4x12x4 (read
/// from that run; it would need about 120 more to stop by its budget).
const TARGET: f64 = 0.8;

/// Runs `make(dir, skip)` without and with the key (the latter on 1 and 3 threads) and checks the
/// two are the same run on exactly the dropped children fewer evaluations.
fn same_run_fewer_evaluations(test: &str, make: impl Fn(&Path, bool) -> RunConfig) {
    let evaluating = run_locally(&make(&scratch_dir(&format!("{test}-off")), false), 1);
    let (skipping, _) = thread_count_blind(&format!("{test}-on"), |dir| make(dir, true));
    assert_eq!(
        evaluating.stop,
        StopReason::TargetReached,
        "the target is reached"
    );
    assert_eq!(evaluating.unchanged_children, 0);
    assert!(
        evaluating.history.iter().any(|r| r.resolution == "4x12x4"),
        "the run reaches its finer level"
    );
    // The same run epoch by epoch, to the last bit of every population...
    assert_eq!(skipping.stop, StopReason::TargetReached);
    assert_eq!(skipping.epochs, evaluating.epochs);
    assert_eq!(epochs(&skipping), epochs(&evaluating));
    assert_eq!(fingerprint(&skipping), fingerprint(&evaluating));
    // ...on exactly the dropped children fewer evaluations, and some were dropped.
    assert!(skipping.unchanged_children > 0);
    assert_eq!(
        skipping.evaluations + skipping.unchanged_children,
        evaluating.evaluations
    );
}

#[test]
fn children_that_make_their_parents_design_are_dropped_and_nothing_else_changes() {
    same_run_fewer_evaluations("unchanged", |dir, skip| {
        config(dir, skip, 3000, Some(TARGET))
    });
}

/// The same with the coarse level judged on the finest grid, whose checks go out beside the next
/// epoch's children: children bred ahead and dropped at the switch leave no count behind.
#[test]
fn copies_bred_ahead_of_a_switch_leave_no_trace() {
    same_run_fewer_evaluations("unchanged-finest", |dir, skip| {
        judged(dir, skip, 3000, Some(TARGET), true)
    });
}

/// The evaluation count at the end of `epoch` in the run store under `dir`.
fn evaluations_after(dir: &Path, epoch: i64) -> u64 {
    let db = rusqlite::Connection::open(dir.join("skipping/run.sqlite")).unwrap();
    let n: i64 = db
        .query_row(
            "SELECT evaluations FROM epoch WHERE epoch = ?1",
            [epoch],
            |r| r.get(0),
        )
        .unwrap();
    n as u64
}

/// A run with the key stopped at the end of an epoch and resumed is the uninterrupted run. One
/// that ended at its budget inside an epoch resumes too (its replay evaluates that epoch's
/// children up to the count the store recorded, in the same order), and then gives the same bits
/// whether it is stopped again on the way or not.
#[test]
fn a_skipping_run_resumes_bit_identical() {
    let whole_dir = scratch_dir("unchanged-whole");
    let whole = run_locally(&config(&whole_dir, true, 400, None), 1);
    assert_eq!(whole.evaluations, 400);
    assert!(whole.unchanged_children > 0);
    let (end_11, end_12) = (
        evaluations_after(&whole_dir, 11),
        evaluations_after(&whole_dir, 12),
    );
    assert!(
        end_12 > end_11 + 1,
        "epoch 12 evaluated at least two children"
    );

    let stopped = scratch_dir("unchanged-stopped");
    let first = run_locally(&config(&stopped, true, end_12, None), 1);
    assert_eq!((first.evaluations, first.epochs), (end_12, 12));
    let resumed = resume_locally(&config(&stopped, true, 400, None), 2);
    assert_eq!(fingerprint(&resumed), fingerprint(&whole));
    assert_eq!(resumed.unchanged_children, whole.unchanged_children);

    // Cut inside epoch 12, then extended to 400 in one go...
    let cut = |dir: &Path| {
        let cut = run_locally(&config(dir, true, end_12 - 1, None), 1);
        assert_eq!((cut.evaluations, cut.epochs), (end_12 - 1, 12));
    };
    let once = scratch_dir("unchanged-cut-once");
    cut(&once);
    let extended = resume_locally(&config(&once, true, 400, None), 2);
    assert_eq!(extended.evaluations, 400);
    // ...or stopped again at the end of its epoch 20 on the way.
    let end_20 = evaluations_after(&once, 20);
    let twice = scratch_dir("unchanged-cut-twice");
    cut(&twice);
    let stop = resume_locally(&config(&twice, true, end_20, None), 2);
    assert_eq!((stop.evaluations, stop.epochs), (end_20, 20));
    let again = resume_locally(&config(&twice, true, 400, None), 1);
    assert_eq!(fingerprint(&again), fingerprint(&extended));
}
