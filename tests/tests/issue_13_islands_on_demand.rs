//! Issue 13, islands on demand (`search.split_after_stall`): the run breeds one population of
//! islands × population until its best stalls at the finest resolution, then deals it by rank into
//! the configured islands; the batch never changes, the split is retraced on resume, and a run
//! that never stalls is the one-island run of the same total, bit for bit.

use amorph_coordinator::RunConfig;
use amorph_tests::{
    circular_arc, fingerprint, resume_locally, run_locally, scratch_dir, thread_count_blind,
};
use std::path::Path;

/// Three islands of 4 on demand (one of 12 until the split), after a coarse level that gives way
/// at 60 evaluations. `min_improvement = 0.5` makes nearly every epoch a stall, so the run splits
/// two epochs into the finest level, well inside the budget.
fn on_demand(results_dir: &Path, evaluations: u64, split_after_stall: usize) -> RunConfig {
    beam(results_dir, evaluations, 3, 4, split_after_stall)
}

fn beam(
    results_dir: &Path,
    evaluations: u64,
    islands: usize,
    population: usize,
    split_after_stall: usize,
) -> RunConfig {
    let sections = format!(
        r#"
[search]
population = {population}
islands = {islands}
children_per_epoch = {population}
initial_points = 20
split_after_stall = {split_after_stall}
[search.migration]
interval = 0
[budget]
evaluations = {evaluations}
[resolution]
levels = [[3, 9, 3], [4, 12, 4]]
stall_epochs = 1000
min_improvement = 0.5
latest_switch = [60]
"#
    );
    circular_arc("on-demand", 3, results_dir, &sections)
}

#[test]
fn one_population_splits_by_rank_once_the_finest_level_stalls() {
    let (one, config) = thread_count_blind("on-demand", |dir| on_demand(dir, 264, 2));
    assert_eq!(one.evaluations, 264);
    assert_eq!(one.populations.len(), 3);
    assert!(one.populations.iter().all(|p| p.len() == 4));

    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let epochs: Vec<(i64, i64, String, i64)> = {
        let mut stmt = db
            .prepare(
                "SELECT e.epoch, e.evaluations, e.resolution, COUNT(DISTINCT p.island)
                 FROM epoch e JOIN population p USING (epoch) GROUP BY e.epoch ORDER BY e.epoch",
            )
            .unwrap();
        (stmt
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))
            .unwrap())
        .map(Result::unwrap)
        .collect()
    };
    // One island until the split, three after. The switch's re-evaluation is the finest level's
    // first observation (progress by definition); its first two epochs are stalls, so the split
    // comes at the end of the second and the third has three islands.
    let split = epochs.iter().find(|e| e.3 == 3).expect("the run split").0;
    assert!(
        epochs.iter().all(|e| (e.3 == 3) == (e.0 >= split)),
        "{epochs:?}"
    );
    let first_fine = epochs.iter().find(|e| e.2 == "4x12x4").unwrap().0;
    assert_eq!(split, first_fine + 2, "{epochs:?}");
    // The same batch of 12 children every epoch, one island or three (plus the 12 designs
    // re-evaluated at the switch).
    for w in epochs.windows(2) {
        let extra = if w[1].0 == first_fine { 12 } else { 0 };
        assert_eq!(w[1].1 - w[0].1, 12 + extra, "{epochs:?}");
    }

    // Dealt by rank: an individual of the last unsplit epoch that is still in its slot after the
    // first split epoch sits on island (its rank mod 3); everyone else there is a new child.
    let population = |epoch: i64| -> Vec<(i64, i64, Option<f64>)> {
        let mut stmt = db
            .prepare("SELECT island, task_id, fitness FROM population WHERE epoch = ?1 ORDER BY island, slot")
            .unwrap();
        (stmt
            .query_map([epoch], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .unwrap())
        .map(Result::unwrap)
        .collect()
    };
    let whole = population(split - 1);
    assert_eq!(whole.len(), 12);
    let mut ranked: Vec<usize> = (0..12).collect();
    let rank = |f: Option<f64>| f.unwrap_or(f64::NEG_INFINITY);
    ranked.sort_by(|&a, &b| {
        rank(whole[b].2)
            .total_cmp(&rank(whole[a].2))
            .then(a.cmp(&b))
    });
    let after = population(split);
    let mut kept = 0;
    for &(island, task, _) in &after {
        match ranked.iter().position(|&s| whole[s].1 == task) {
            Some(r) => {
                assert_eq!(island, (r % 3) as i64, "rank {r} on island {island}");
                kept += 1;
            }
            None => {
                let bred: i64 = db
                    .query_row(
                        "SELECT epoch FROM evaluation WHERE task_id = ?1",
                        [task],
                        |r| r.get(0),
                    )
                    .unwrap();
                assert_eq!(
                    bred, split,
                    "task {task} is neither dealt nor bred at the split"
                );
            }
        }
    }
    assert!(kept >= 6, "crowding replaced {} of 12 at once", 12 - kept);

    // Stopped two epochs before the first split one (the split follows the epoch before it) and
    // resumed: the replay retraces the split.
    let resumed_dir = scratch_dir("on-demand-resumed");
    let stop_at = epochs.iter().find(|e| e.0 == split - 2).unwrap().1 as u64;
    let first = run_locally(&on_demand(&resumed_dir, stop_at, 2), 1);
    assert_eq!(first.populations.len(), 1);
    let resumed = resume_locally(&on_demand(&resumed_dir, 264, 2), 2);
    assert_eq!(fingerprint(&resumed), fingerprint(&one));
}

/// A run that never stalls long enough to split is the one-island run of the same total
/// population and batch, bit for bit: islands on demand cost nothing until they are used.
#[test]
fn a_run_that_never_splits_is_one_island_of_the_whole() {
    let dir = scratch_dir("never-split");
    let never = run_locally(&on_demand(&dir, 264, 1000), 2);
    assert_eq!(never.populations.len(), 1);
    let whole = beam(&scratch_dir("one-island-of-12"), 264, 1, 12, 0);
    assert_eq!(fingerprint(&run_locally(&whole, 2)), fingerprint(&never));
}
