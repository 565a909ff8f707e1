//! Issue 13: the coarse level judged on the finest grid (`resolution.stall_on_finest`), and its
//! checks sent out with the next epoch's children (`resolution.overlap_finest_checks`) so that
//! the workers a single check leaves idle work meanwhile, without changing a bit of the run.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use amorph::voxel::GridDims;
use amorph_coordinator::evaluator::{Completion, EvaluatorError};
use amorph_coordinator::progress::Progress;
use amorph_coordinator::store::RunStore;
use amorph_coordinator::{
    Evaluator, LocalEvaluator, RunConfig, RunContext, RunSummary, StopReason, Task, run,
};
use amorph_tests::{
    ClusterRun, TestWorker, circular_arc, fingerprint, resume_locally, run_locally, scratch_dir,
    thread_count_blind,
};

/// Two islands on the circular arc, 4×12×4 then 6×18×6 with the stall rule watching the finest
/// grid; `overlap` sends each check out with the next epoch's children.
fn finest_config(results_dir: &Path, evaluations: u64, overlap: bool) -> RunConfig {
    checking_config(results_dir, 5, evaluations, overlap, false)
}

/// `finest_config` with its seed, and `carry` for `resolution.carry_checked_best`.
fn checking_config(
    results_dir: &Path,
    seed: u64,
    evaluations: u64,
    overlap: bool,
    carry: bool,
) -> RunConfig {
    let sections = format!(
        r#"
[search]
population = 8
islands = 2
children_per_epoch = 6
initial_points = 40
[search.local_search]
fraction = 0.5
step = 0.02
shared = true
[budget]
evaluations = {evaluations}
[resolution]
levels = [[4, 12, 4], [6, 18, 6]]
stall_epochs = 3
min_improvement = 0.02
stall_on_finest = true
overlap_finest_checks = {overlap}
carry_checked_best = {carry}
"#
    );
    circular_arc("finest", seed, results_dir, &sections)
}

/// `resolution.stall_on_finest`: at the coarse level the run's best is evaluated at the finest
/// level each time it changes, and the switch comes when those scores stall, exactly where the
/// stall rule applied to the stored checks puts it; the run is bit-identical on 1 and 3 threads
/// and when interrupted at the coarse level and resumed.
#[test]
fn a_coarse_level_gives_way_when_its_best_stops_improving_on_the_finest_grid() {
    let (one, config) = thread_count_blind("finest", |dir| finest_config(dir, 400, true));

    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let query = |sql: &str| -> Vec<(i64, String, String, f64)> {
        let mut stmt = db.prepare(sql).unwrap();
        stmt.query_map([], |r| {
            Ok((
                r.get(0)?,
                r.get(1)?,
                r.get(2)?,
                r.get::<_, Option<f64>>(3)?.unwrap_or(f64::NEG_INFINITY),
            ))
        })
        .unwrap()
        .map(Result::unwrap)
        .collect()
    };
    let checks = query(
        "SELECT epoch, resolution, genome, fitness FROM evaluation
         WHERE purpose = 'finest_check' ORDER BY task_id",
    );
    let switch = query(
        "SELECT epoch, resolution, genome, fitness FROM evaluation WHERE purpose = 'reevaluation'",
    );
    assert_eq!(switch.len(), 16, "both islands re-evaluated once");
    let switch = switch[0].0;
    // Checks happen at the coarse level only, at the finest resolution, one per epoch at most,
    // never twice in a row on the same genome.
    assert!(checks.len() >= 2, "{checks:?}");
    assert!(
        checks
            .iter()
            .all(|c| c.1 == "6x18x6" && (1..=switch).contains(&c.0))
    );
    assert!(
        checks
            .windows(2)
            .all(|w| w[0].0 < w[1].0 && w[0].2 != w[1].2)
    );
    // The stall rule on the checks' running best gives the switch's epoch.
    let (mut last_progress, mut without, mut expected) = (f64::NEG_INFINITY, 0, None);
    let mut watched = f64::NEG_INFINITY;
    for epoch in 1..=switch {
        for c in checks.iter().filter(|c| c.0 == epoch) {
            watched = watched.max(c.3);
        }
        let threshold = last_progress + 0.02 * last_progress.abs();
        if watched > threshold || !last_progress.is_finite() {
            (last_progress, without) = (watched, 0);
        } else {
            without += 1;
        }
        if without >= 3 {
            expected = Some(epoch);
            break;
        }
    }
    assert_eq!(expected, Some(switch), "checks {checks:?}");

    // Stopped at the end of the second check's epoch, before that check (the budget has no room
    // left for it), then extended: the resumed session replays the first check and makes the
    // second.
    let stop_at: i64 = db
        .query_row(
            "SELECT evaluations FROM epoch WHERE epoch = ?1",
            [checks[1].0],
            |r| r.get(0),
        )
        .unwrap();
    let stop_at = stop_at as u64;
    let resumed_dir = scratch_dir("finest-resumed");
    let first = run_locally(&finest_config(&resumed_dir, stop_at, true), 1);
    assert_eq!(first.evaluations, stop_at);
    let extended = finest_config(&resumed_dir, 400, true);
    let resumed = resume_locally(&extended, 2);
    assert_eq!(fingerprint(&resumed), fingerprint(&one));
}

/// Local threads that note the resolutions of every batch they are handed.
struct Recording {
    threads: LocalEvaluator,
    batches: Vec<Vec<GridDims>>,
}

impl Evaluator for Recording {
    fn evaluate(
        &mut self,
        tasks: &[Task],
        on_done: &(dyn Fn(&Task, &Completion) + Sync),
    ) -> Result<Vec<Completion>, EvaluatorError> {
        self.batches.push(tasks.iter().map(|t| t.dims).collect());
        self.threads.evaluate(tasks, on_done)
    }
}

/// What a run store holds of a run apart from times and places: every evaluation (task, epoch,
/// island, purpose, resolution, genome, outcome), every epoch (evaluations, resolution, best) and
/// every recorded population.
fn stored(config: &RunConfig) -> Vec<String> {
    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let rows = |sql: &str| -> Vec<String> {
        let mut stmt = db.prepare(sql).unwrap();
        let columns = stmt.column_count();
        stmt.query_map([], |r| {
            Ok((0..columns)
                .map(|i| format!("{:?}", r.get_ref(i).unwrap()))
                .collect::<Vec<_>>()
                .join("|"))
        })
        .unwrap()
        .map(Result::unwrap)
        .collect()
    };
    [
        "SELECT task_id, epoch, island, purpose, resolution, genome, outcome FROM evaluation ORDER BY task_id",
        "SELECT epoch, evaluations, resolution, best_fitness FROM epoch ORDER BY epoch",
        "SELECT epoch, island, slot, task_id, fitness FROM population ORDER BY epoch, island, slot",
    ]
    .iter()
    .flat_map(|sql| rows(sql))
    .collect()
}

/// A check at the finest level goes out with the next epoch's children. Where the level goes on,
/// those are the children the epoch breeds; where the check ends the level, they are dropped and
/// the re-evaluation takes their task numbers. Either way the run is the one without overlap,
/// to the bit, populations and run store alike (only times differ), on any thread count.
#[test]
fn checks_sent_out_with_the_next_children_change_no_bit() {
    let plain = finest_config(&scratch_dir("plain"), 400, false);
    let plain_run = run_locally(&plain, 1);

    let overlapped = finest_config(&scratch_dir("overlapped"), 400, true);
    let store = RunStore::create(&overlapped, true).unwrap();
    let mut recording = Recording {
        threads: LocalEvaluator::new(std::sync::Arc::new(overlapped.raw.scene.clone()), 3),
        batches: Vec::new(),
    };
    let ctx = RunContext {
        store: &store,
        shutdown: &AtomicBool::new(false),
        progress: &Progress::hidden(),
    };
    let overlapped_run: RunSummary = run(&overlapped, &mut recording, &ctx).unwrap();

    assert_eq!(fingerprint(&overlapped_run), fingerprint(&plain_run));
    assert_eq!(overlapped_run.evaluations, plain_run.evaluations);
    assert_eq!(stored(&overlapped), stored(&plain));

    let (coarse, finest) = (GridDims::new(4, 12, 4), GridDims::new(6, 18, 6));
    let with_children: Vec<usize> = (recording.batches.iter().enumerate())
        .filter(|(_, b)| b[0] == finest && b.len() > 1 && b[1..].iter().all(|&d| d == coarse))
        .map(|(i, _)| i)
        .collect();
    let checks_alone = (recording.batches.iter())
        .filter(|b| b.len() == 1 && b[0] == finest)
        .count();
    let switch = (recording.batches.iter())
        .position(|b| b.len() == 16 && b.iter().all(|&d| d == finest))
        .expect("the switch re-evaluates both islands at the finest level");
    // Every check went out with children (the budget always had room for them), at least one
    // of them kept, and the last, the one that ended the level, dropped: the re-evaluation comes
    // next, and the run above is the same.
    assert_eq!(checks_alone, 0, "{:?}", recording.batches);
    assert!(with_children.len() >= 2, "{:?}", recording.batches);
    assert_eq!(
        with_children.last(),
        Some(&(switch - 1)),
        "{:?}",
        recording.batches
    );
}

/// The same through the cluster: two gRPC workers, whose outcomes are claims (each check and
/// each child that would replace a parent is evaluated again by the other before it counts),
/// take the check and the coarse children from one batch, and the run is the in-process run
/// without overlap, bit for bit, run store included.
#[test]
fn two_grpc_workers_give_the_overlapped_run_bit_for_bit() {
    let plain = finest_config(&scratch_dir("grpc-plain"), 400, false);
    let plain_run = run_locally(&plain, 1);
    let config = finest_config(&scratch_dir("grpc-overlapped"), 400, true);
    let run = ClusterRun::start(&config, 0, None);
    let a = TestWorker::start(&run.url(), 1, None);
    let b = TestWorker::start(&run.url(), 1, None);
    let summary = run.join();
    assert_eq!(fingerprint(&summary), fingerprint(&plain_run));
    assert_eq!(stored(&config), stored(&plain));
    let (a, b) = (a.join().unwrap(), b.join().unwrap());
    assert!(a.evaluated > 0 && b.evaluated > 0, "{a:?} {b:?}");
}

/// A stored evaluation's task, epoch, island, purpose, genome and fitness (-inf for a failure).
type Row = (i64, i64, i64, String, String, f64);

fn evaluations(config: &RunConfig) -> Vec<Row> {
    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let mut stmt = db
        .prepare(
            "SELECT task_id, epoch, island, purpose, genome, fitness FROM evaluation ORDER BY task_id",
        )
        .unwrap();
    stmt.query_map([], |r| {
        let fitness: Option<f64> = r.get(5)?;
        Ok((
            r.get(0)?,
            r.get(1)?,
            r.get(2)?,
            r.get(3)?,
            r.get(4)?,
            fitness.unwrap_or(f64::NEG_INFINITY),
        ))
    })
    .unwrap()
    .map(Result::unwrap)
    .collect()
}

/// The best fitness recorded at the end of each epoch after `epoch`.
fn bests_after(config: &RunConfig, epoch: i64) -> Vec<f64> {
    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let mut stmt = db
        .prepare("SELECT best_fitness FROM epoch WHERE epoch > ?1 ORDER BY epoch")
        .unwrap();
    stmt.query_map([epoch], |r| r.get::<_, f64>(0))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// `resolution.carry_checked_best`: on a seed where the coarse level climbed past the design its
/// checks ranked best, so that the switch's re-evaluated populations hold nothing as good, that
/// design joins the finest level anyway, at no evaluation: the run is the plain one up to the
/// switch, evaluation for evaluation, spends the same budget, breeds differently from there, and
/// its best at the finest level is never worse than the best check. Bit-identical on 1
/// and 3 threads, and when stopped at the switch for want of budget and resumed with more (the
/// resumed session rebuilds the carried design from the replayed checks).
#[test]
fn the_best_checked_design_is_carried_into_the_finest_level() {
    let seed = 5;
    let (whole, carried) =
        thread_count_blind("carry", |dir| checking_config(dir, seed, 400, true, true));
    let plain = checking_config(&scratch_dir("carry-plain"), seed, 400, true, false);
    run_locally(&plain, 1);
    let (carried_rows, plain_rows) = (evaluations(&carried), evaluations(&plain));
    assert_eq!(carried_rows.len(), plain_rows.len(), "the same budget");

    let switch: Vec<&Row> = plain_rows
        .iter()
        .filter(|r| r.3 == "reevaluation")
        .collect();
    let (switch_epoch, last_task) = (switch[0].1, switch.last().unwrap().0);
    let before =
        |rows: &[Row]| -> Vec<Row> { rows.iter().filter(|r| r.0 <= last_task).cloned().collect() };
    assert_eq!(before(&carried_rows), before(&plain_rows));

    // The first check of the best rank, as the run keeps it.
    let best_check = (plain_rows.iter().filter(|r| r.3 == "finest_check"))
        .reduce(|a, b| if b.5 > a.5 { b } else { a })
        .expect("checks at the coarse level");
    let reevaluated_best = switch.iter().map(|r| r.5).fold(f64::NEG_INFINITY, f64::max);
    assert!(
        reevaluated_best < best_check.5,
        "seed {seed} does not leave its best check behind: re-evaluated {reevaluated_best}, checked {}",
        best_check.5
    );
    assert!(
        !switch
            .iter()
            .any(|r| r.2 == best_check.2 && r.4 == best_check.4),
        "the checked design is no longer in its island"
    );
    let after =
        |rows: &[Row]| -> Vec<Row> { rows.iter().filter(|r| r.0 > last_task).cloned().collect() };
    assert_ne!(
        after(&carried_rows),
        after(&plain_rows),
        "the carried design changed the breeding"
    );
    let carried_bests = bests_after(&carried, switch_epoch);
    assert!(!carried_bests.is_empty());
    assert!(
        carried_bests.iter().all(|&b| b >= best_check.5),
        "{carried_bests:?} against the best check {}",
        best_check.5
    );

    // Stopped where the switch's re-evaluation no longer fits the budget, then extended, with
    // the key and without: the stopped run ends at the stall, and the extended one switches
    // there as the run with the larger budget did.
    let plain_whole = run_locally(&plain, 1);
    for (carry, whole) in [(false, &plain_whole), (true, &whole)] {
        let resumed_dir = scratch_dir(&format!("carry-resumed-{carry}"));
        // Every evaluation before the switch's re-evaluation (the check that ended the level
        // too), and room for a few more but not for the re-evaluation: once bred at the coarse
        // level, they made the extended run a different one.
        let before_switch = plain_rows.iter().filter(|r| r.0 < switch[0].0).count() as u64;
        let stop_at = before_switch + switch.len() as u64 / 2;
        let first = run_locally(
            &checking_config(&resumed_dir, seed, stop_at, true, carry),
            1,
        );
        assert_eq!(first.evaluations, before_switch);
        assert_eq!(first.stop, StopReason::EvaluationBudget);
        assert!(
            first
                .history
                .iter()
                .all(|r| r.epoch <= switch_epoch as usize)
        );
        let resumed = resume_locally(&checking_config(&resumed_dir, seed, 400, true, carry), 2);
        assert_eq!(fingerprint(&resumed), fingerprint(whole), "carry {carry}");
    }
}
