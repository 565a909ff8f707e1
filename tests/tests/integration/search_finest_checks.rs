//! The coarse level judged on the finest grid (`resolution.stall_on_finest`), and its checks sent
//! out with the next epoch's children so that the workers a single check leaves idle work
//! meanwhile, without changing a bit of the run.

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
    ClusterRun, TestWorker, fingerprint, resume_locally, run_locally, scratch_dir, test_config,
    thread_count_blind,
};

/// Two islands on the circular arc, 4×12×4 then 6×18×6 with the stall rule watching the finest
/// grid.
fn finest_config(results_dir: &Path, evaluations: u64) -> RunConfig {
    test_config(
        "circular_arc",
        results_dir,
        &[
            "name=finest",
            "seed=5",
            "search.population=8",
            "search.islands=2",
            "search.children_per_epoch=6",
            "search.initial_points=40",
            "search.local_search.fraction=0.5",
            "search.local_search.step=0.02",
            "search.local_search.shared=true",
            &format!("budget.evaluations={evaluations}"),
            "resolution.levels=[[4, 12, 4], [6, 18, 6]]",
            "resolution.stall_epochs=3",
            "resolution.min_improvement=0.02",
            "resolution.stall_on_finest=true",
        ],
    )
}

/// `resolution.stall_on_finest`: at the coarse level the run's best is evaluated at the finest
/// level each time it changes, and the switch comes when those scores stall, exactly where the
/// stall rule applied to the stored checks puts it; the run is bit-identical on 1 and 3 threads
/// and when interrupted at the coarse level and resumed.
#[test]
fn a_coarse_level_gives_way_when_its_best_stops_improving_on_the_finest_grid() {
    let (one, config) = thread_count_blind("finest", |dir| finest_config(dir, 400));

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
    let first = run_locally(&finest_config(&resumed_dir, stop_at), 1);
    assert_eq!(first.evaluations, stop_at);
    let extended = finest_config(&resumed_dir, 400);
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
/// the re-evaluation takes their task numbers. Either way the run is the same bits, populations
/// and run store alike (only times differ), whatever evaluates the batches.
#[test]
fn checks_sent_out_with_the_next_children_change_no_bit() {
    let plain = finest_config(&scratch_dir("plain"), 400);
    let plain_run = run_locally(&plain, 1);

    let overlapped = finest_config(&scratch_dir("overlapped"), 400);
    let store = RunStore::create(&overlapped, true).unwrap();
    let mut recording = Recording {
        threads: LocalEvaluator::new(std::sync::Arc::new(overlapped.scene.clone()), 3),
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
/// take the check and the coarse children from one batch, and the run is the in-process run,
/// bit for bit, run store included.
#[test]
fn two_grpc_workers_give_the_in_process_run_bit_for_bit() {
    let plain = finest_config(&scratch_dir("grpc-plain"), 400);
    let plain_run = run_locally(&plain, 1);
    let config = finest_config(&scratch_dir("grpc-overlapped"), 400);
    let run = ClusterRun::start(&config, 0, None);
    let a = TestWorker::start(&run.url(), 1, None);
    let b = TestWorker::start(&run.url(), 1, None);
    let summary = run.join();
    assert_eq!(fingerprint(&summary), fingerprint(&plain_run));
    assert_eq!(stored(&config), stored(&plain));
    let (a, b) = (a.join().unwrap(), b.join().unwrap());
    assert!(a.evaluated > 0 && b.evaluated > 0, "{a:?} {b:?}");
}

/// A stored evaluation's task and purpose.
fn purposes(config: &RunConfig) -> Vec<(i64, String)> {
    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let mut stmt = db
        .prepare("SELECT task_id, purpose FROM evaluation ORDER BY task_id")
        .unwrap();
    stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// A run whose budget ends where the switch's re-evaluation no longer fits stops at the stall;
/// resumed with the larger budget it switches there as the run with that budget from the start
/// did, to the same bits.
#[test]
fn a_switch_the_budget_cannot_afford_ends_the_run_and_resumes_bit_identical() {
    let whole_config = finest_config(&scratch_dir("switch-whole"), 400);
    let whole = run_locally(&whole_config, 1);
    let rows = purposes(&whole_config);
    let switch: Vec<i64> = (rows.iter())
        .filter(|r| r.1 == "reevaluation")
        .map(|r| r.0)
        .collect();
    // Every evaluation before the switch's re-evaluation (the check that ended the level too),
    // and room for a few more but not for the re-evaluation.
    let before_switch = rows.iter().filter(|r| r.0 < switch[0]).count() as u64;
    let stop_at = before_switch + switch.len() as u64 / 2;
    let dir = scratch_dir("switch-resumed");
    let first = run_locally(&finest_config(&dir, stop_at), 1);
    assert_eq!(first.evaluations, before_switch);
    assert_eq!(first.stop, StopReason::EvaluationBudget);
    let resumed = resume_locally(&finest_config(&dir, 400), 2);
    assert_eq!(fingerprint(&resumed), fingerprint(&whole));
}
