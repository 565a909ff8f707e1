//! Issue 13: the search's new operators (nudges of the best, the 1/5th-rule step, crossover planes
//! across the beam, migration into the most similar slot) keep a run bit-identical whatever the
//! number of evaluation threads, keep the adapted step within its bounds, and never lose an
//! island's best; `diversity.csv` records every island after every epoch.

use amorph::genome::Genome;
use amorph_coordinator::RunConfig;
use amorph_tests::{
    circular_arc, fingerprint, resume_locally, run_locally, scratch_dir, thread_count_blind,
};
use std::path::Path;

fn config(results_dir: &Path, seed: u64, local_search: &str) -> RunConfig {
    let sections = format!(
        r#"
[search]
population = 10
islands = 3
children_per_epoch = 10
initial_points = 20
[search.migration]
interval = 2
topology = {{ kind = "ring" }}
replacement = "most_similar"
[search.local_search]
fraction = 0.3
step = 0.02
{local_search}
[search.step_adaptation]
rule = "one_fifth"
factor = 1.5
min_scale = 0.25
max_scale = 2.0
[search.crossover]
across_probability = 0.5
[budget]
evaluations = 240
[resolution]
levels = [[4, 12, 4]]
"#
    );
    circular_arc("operators", seed, results_dir, &sections)
}

/// One climb fed by every island (`shared`, with insertions, the improving nudges of each epoch
/// combined into one child of the next): the nudges of three islands go to the one holding the
/// run's best, and the run stays bit-identical whatever the thread count, its best never worse
/// from one epoch to the next.
#[test]
fn a_shared_climb_is_bit_identical_on_1_and_3_threads_and_never_loses_the_best() {
    let dirs = [scratch_dir("shared-1"), scratch_dir("shared-3")];
    let configs = dirs
        .each_ref()
        .map(|d| config(d, 7, "insertion = 0.5\nshared = true\ncombine = true"));
    let one = run_locally(&configs[0], 1);
    let three = run_locally(&configs[1], 3);
    assert_eq!(one.evaluations, 240);
    assert_eq!(one.populations, three.populations);
    let history = std::fs::read_to_string(configs[0].run_dir().join("history.csv")).unwrap();
    let mut run_best = Vec::<f64>::new();
    for row in history.lines().skip(1) {
        let fields: Vec<&str> = row.split(',').collect();
        // An island whose every design failed has no best yet (an empty field).
        let (Ok(epoch), Ok(best)) = (fields[0].parse::<usize>(), fields[5].parse::<f64>()) else {
            continue;
        };
        if run_best.len() <= epoch {
            run_best.resize(epoch + 1, f64::NEG_INFINITY);
        }
        run_best[epoch] = run_best[epoch].max(best);
    }
    let epochs: Vec<f64> = run_best.into_iter().filter(|b| b.is_finite()).collect();
    assert!(epochs.len() > 5, "{history}");
    assert!(
        epochs.windows(2).all(|w| w[1] >= w[0]),
        "the run's best got worse: {epochs:?}"
    );
}

/// A climb key's contract: with `keys` added to `climb`, the shared climb (most children nudges of
/// the best, as in the arc's runs, so that epochs have several nudges to add up) is bit-identical
/// on 1 and 3 threads and when stopped at an epoch's end and resumed (the offered designs are
/// rebuilt from the replayed epoch); the keys reach the search (another run than `climb` alone);
/// and `climb` with `defaults` written out is `climb`'s run to the bit.
fn assert_a_climb_key(name: &str, climb: &str, keys: &str, defaults: &str) {
    let config = |dir: &Path, keys: &str| {
        let mut config = config(dir, 7, keys);
        config.raw.search.local_search.fraction = 0.8;
        config
    };
    let run = |tag: &str, keys: &str, threads: usize| {
        let dir = scratch_dir(&format!("{name}-{tag}"));
        fingerprint(&run_locally(&config(&dir, keys), threads))
    };
    let with = format!("{climb}\n{keys}");
    let one = run("1", &with, 1);
    assert!(one == run("3", &with, 3), "{name}: 1 and 3 threads differ");
    let without = run("without", climb, 1);
    assert!(one != without, "{name}: the keys breed the same run");
    let explicit = format!("{climb}\n{defaults}");
    assert!(
        without == run("defaults", &explicit, 2),
        "{name}: the defaults changed the run"
    );

    // Stopped at the end of an epoch (30 initial + 3 epochs of 30) and resumed to 240.
    let dir = scratch_dir(&format!("{name}-resumed"));
    let mut stopped = config(&dir, &with);
    stopped.raw.budget.evaluations = Some(120);
    assert_eq!(run_locally(&stopped, 2).evaluations, 120);
    let resumed = resume_locally(&config(&dir, &with), 3);
    assert!(
        fingerprint(&resumed) == one,
        "{name}: the resumed run differs"
    );
}

/// Several combinations, built on the design that won the slot (`combinations = 3`, `rebase =
/// true`, session 37); `combinations = 1` without `rebase` is the one-combination run.
#[test]
fn several_rebased_combinations_are_bit_identical_on_threads_and_resume() {
    assert_a_climb_key(
        "combinations",
        "insertion = 0.5\nshared = true\ncombine = true",
        "combinations = 3\nrebase = true",
        "combinations = 1\nrebase = false",
    );
}

/// Nudge steps spread over octaves (`step_spread`, session 42): the draw comes from the island's
/// stream, so the run is bit-identical on 1 and 3 threads; the key reaches the search (another run
/// than the fixed step), and `step_spread = 0` written out is the fixed-step run to the bit.
#[test]
fn a_spread_nudge_step_is_bit_identical_on_threads_and_zero_is_the_fixed_step() {
    let climb = "insertion = 0.5\nshared = true\ncombine = true";
    let run = |name: &str, keys: &str, threads: usize| {
        fingerprint(&run_locally(&config(&scratch_dir(name), 7, keys), threads))
    };
    let spread = format!("{climb}\nstep_spread = 2.0");
    let one = run("spread-1", &spread, 1);
    assert!(one == run("spread-3", &spread, 3), "1 and 3 threads differ");
    let fixed = run("spread-fixed", climb, 2);
    assert!(one != fixed, "a spread step breeds another run");
    let zero = format!("{climb}\nstep_spread = 0.0");
    assert!(
        fixed == run("spread-zero", &zero, 1),
        "a spread of 0 changed the run"
    );
}

/// Nudges picked by the residual model (`combine_by = "residuals"`, session 43), rebased: the
/// pick is rebuilt from the replayed epoch's outcomes; `combine_by = "fitness"` written out is the
/// improving nudges' combination.
#[test]
fn nudges_picked_by_their_residuals_are_bit_identical_on_threads_and_resume() {
    assert_a_climb_key(
        "residuals",
        "insertion = 0.5\nshared = true\ncombine = true\nrebase = true",
        "combine_by = \"residuals\"",
        "combine_by = \"fitness\"",
    );
}

/// The residual model's least-squares step (`combine_by = "least_squares"`, session 44), with
/// its halvings: the coefficients come from a fixed-order descent on the replayed epoch's
/// outcomes, so the run is the same on 1 and 3 threads and across a resume, and another run than
/// the improving nudges' combination.
#[test]
fn a_least_squares_step_is_bit_identical_on_threads_and_resume() {
    assert_a_climb_key(
        "least-squares",
        "insertion = 0.5\nshared = true\ncombine = true\nrebase = true\ncombinations = 3",
        "combine_by = \"least_squares\"\nreach = 2.0",
        "combine_by = \"fitness\"",
    );
}

/// Insertions drawn by the beam's flip model (`insertion_by = "flip_model"`, session 45): the
/// guide is built from the best's stored outcome, so the run is the same on 1 and 3 threads and
/// across a resume, and another run than uniform insertions; `insertion_by = "random"` written
/// out is the uniform run to the bit.
#[test]
fn insertions_drawn_by_the_flip_model_are_bit_identical_on_threads_and_resume() {
    assert_a_climb_key(
        "flip-model",
        "insertion = 0.5\nshared = true\ncombine = true",
        "insertion_by = \"flip_model\"",
        "insertion_by = \"random\"",
    );
}

/// The flip model's steps (`model_steps`, session 45): the sequence is rebuilt from the best's
/// stored outcome, so the run is the same on 1 and 3 threads and across a resume, and another run
/// than guided insertions alone; `model_steps = 0` written out is that run to the bit.
#[test]
fn model_steps_are_bit_identical_on_threads_and_resume() {
    assert_a_climb_key(
        "model-steps",
        "insertion = 0.5\nshared = true\ncombine = true\ninsertion_by = \"flip_model\"",
        "model_steps = 3",
        "model_steps = 0",
    );
}

#[test]
fn new_operators_are_bit_identical_on_1_and_3_threads_and_keep_their_bounds() {
    let dirs = [scratch_dir("operators-1"), scratch_dir("operators-3")];
    let configs = dirs.each_ref().map(|d| config(d, 5, ""));
    let one = run_locally(&configs[0], 1);
    let three = run_locally(&configs[1], 3);
    assert_eq!(one.evaluations, 240);
    assert_eq!(one.populations, three.populations);

    let limits = *configs[0].raw.scene.limits();
    let materials = configs[0].raw.scene.palette().len();
    for ind in one.populations.iter().flatten() {
        let genome: &Genome = &ind.genome;
        genome.validate(&limits, materials).expect("within limits");
    }

    // The history's per-island best never gets worse: nudges and migrants enter only by beating
    // the occupant they replace.
    let history = std::fs::read_to_string(configs[0].run_dir().join("history.csv")).unwrap();
    for island in 0..3 {
        // An island whose members have all failed so far has no best fitness (an empty cell);
        // once it has one it keeps one.
        let best: Vec<Option<f64>> = history
            .lines()
            .skip(1)
            .filter(|l| l.split(',').nth(4) == Some(&island.to_string()))
            .map(|l| l.split(',').nth(5).and_then(|v| v.parse().ok()))
            .collect();
        assert_eq!(best.len(), one.epochs, "island {island}");
        assert!(best.last().is_some_and(|b| b.is_some()), "{best:?}");
        assert!(
            best.windows(2).all(|w| match (w[0], w[1]) {
                (Some(a), Some(b)) => b >= a,
                (Some(_), None) => false,
                (None, _) => true,
            }),
            "{best:?}"
        );
    }

    // diversity.csv: a row per island per epoch; the step scale moves only by the factor and
    // within its bounds; within-island distances are finite and non-negative.
    let text = std::fs::read_to_string(configs[0].run_dir().join("diversity.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 3 * one.epochs);
    let scales: Vec<f64> = rows.iter().map(|r| r[7]).collect();
    assert!(
        scales.iter().all(|s| (0.25..=2.0).contains(s)),
        "{scales:?}"
    );
    assert!(
        scales.iter().any(|&s| s != 1.0),
        "the step adapted at least once: {scales:?}"
    );
    for island in 0..3 {
        let mine: Vec<f64> = rows
            .iter()
            .filter(|r| r[2] == island as f64)
            .map(|r| r[7])
            .collect();
        for w in mine.windows(2) {
            let ratio = w[1] / w[0];
            let allowed = [1.0, 1.5, 1.0 / 1.5];
            let clamped = w[1] == 0.25 || w[1] == 2.0;
            assert!(
                clamped || allowed.iter().any(|a| (ratio - a).abs() < 1e-12),
                "island {island}: {} -> {}",
                w[0],
                w[1]
            );
        }
    }
    assert!(
        rows.iter()
            .all(|r| r[3].is_finite() && r[3] >= 0.0 && r[4] >= 0.0)
    );
    // Design distances are shares of voxels, and the island holding the run's best is at 0.
    assert!(
        rows.iter()
            .all(|r| (0.0..=1.0).contains(&r[5]) && (0.0..=1.0).contains(&r[6]))
    );
    let last_epoch = one.epochs as f64;
    assert!(
        rows.iter()
            .filter(|r| r[0] == last_epoch)
            .any(|r| r[4] == 0.0 && r[6] == 0.0)
    );
}

fn merging_config(results_dir: &Path, evaluations: u64) -> RunConfig {
    let sections = format!(
        r#"
[search]
population = 8
islands = 3
children_per_epoch = 4
initial_points = 20
[search.local_search]
fraction = 0.5
step = 0.02
shared = true
[budget]
evaluations = {evaluations}
[resolution]
levels = [[3, 9, 3], [4, 12, 4]]
stall_epochs = 1000
latest_switch = [100]
merge_islands = true
"#
    );
    circular_arc("merging", 11, results_dir, &sections)
}

/// `resolution.merge_islands`: at the switch the three islands become one, carrying each
/// island's best into the finer grid (8 re-evaluations, not 3 × 8) and breeding all 3 × 4
/// children per epoch from then on; the run is bit-identical on 1 and 3 threads and when
/// interrupted after the merge and resumed (the replay retraces the merge), also from a run that
/// ended at a budget inside an epoch.
#[test]
fn merged_islands_carry_each_islands_best_and_resume_bit_identical() {
    let (one, config) = thread_count_blind("merge", |dir| merging_config(dir, 260));
    assert_eq!(one.evaluations, 260);
    assert_eq!(one.populations.len(), 1);
    let resumed_dir = scratch_dir("merge-resumed");

    // Stopped at 140 evaluations (after the merge at 108 + 8), then extended to 260.
    let first = run_locally(&merging_config(&resumed_dir, 140), 1);
    assert_eq!((first.evaluations, first.populations.len()), (140, 1));
    let extended = merging_config(&resumed_dir, 260);
    let resumed = resume_locally(&extended, 2);
    assert_eq!(fingerprint(&resumed), fingerprint(&one));

    // A run that *ended* at its budget in the middle of an epoch (134 = 128 + 6 of the epoch's 12
    // children) extends too: its replay breeds that last epoch short, as it was, and the run goes
    // on from there (session 32 found such runs refused: "the replayed populations of epoch N
    // differ"). The short epoch is part of its history, so it is not the run above; stopped again
    // at an epoch's end (206 = 134 + 6 × 12) and resumed, it gives the same bits.
    let extend = |stops: &[u64]| {
        let dir = scratch_dir("merge-cut-short");
        let cut = run_locally(&merging_config(&dir, 134), 1);
        assert_eq!(cut.evaluations, 134);
        let mut last = cut;
        for &budget in stops {
            last = resume_locally(&merging_config(&dir, budget), 2);
            assert_eq!(last.evaluations, budget);
        }
        fingerprint(&last)
    };
    assert_eq!(extend(&[260]), extend(&[206, 260]));

    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let rows = |sql: &str| -> Vec<(i64, i64, String)> {
        let mut stmt = db.prepare(sql).unwrap();
        stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .unwrap()
            .map(Result::unwrap)
            .collect()
    };
    // (epoch, island, genome) of every re-evaluation: one switch, as island 0, a population's worth.
    let carried =
        rows("SELECT epoch, island, genome FROM evaluation WHERE purpose = 'reevaluation'");
    assert_eq!(carried.len(), 8);
    let switch = carried[0].0;
    assert!(carried.iter().all(|&(e, i, _)| e == switch && i == 0));
    // Before the switch (epoch `switch` is the last coarse one) three islands, after it one.
    let islands_at = |epoch: i64| {
        db.query_row(
            "SELECT COUNT(DISTINCT island) FROM population WHERE epoch = ?1",
            [epoch],
            |r| r.get::<_, i64>(0),
        )
        .unwrap()
    };
    assert_eq!((islands_at(switch), islands_at(switch + 1)), (3, 1));
    // Every island's coarse best went into the merged population.
    let bests = rows(&format!(
        "SELECT p.island, p.slot, e.genome FROM population p JOIN evaluation e USING (task_id)
         WHERE p.epoch = {switch} AND p.fitness = (SELECT MAX(fitness) FROM population q
         WHERE q.epoch = p.epoch AND q.island = p.island)"
    ));
    for island in 0..3 {
        assert!(
            bests
                .iter()
                .filter(|b| b.0 == island)
                .any(|b| carried.iter().any(|c| c.2 == b.2)),
            "island {island}'s best was not carried"
        );
    }
    // The same batch before and after the merge: 3 islands x 4 children, then one island of 12.
    assert_one_switch(&db, switch, 12, 8);
}

/// Every epoch of the run evaluates `batch` children, and the one that switches resolution at
/// epoch `switch` also its `reevaluations`.
fn assert_one_switch(db: &rusqlite::Connection, switch: i64, batch: i64, reevaluations: i64) {
    let mut stmt = db
        .prepare("SELECT evaluations FROM epoch ORDER BY epoch")
        .unwrap();
    let totals: Vec<i64> = (stmt.query_map([], |r| r.get(0)).unwrap())
        .map(Result::unwrap)
        .collect();
    let steps: Vec<i64> = totals.windows(2).map(|w| w[1] - w[0]).collect();
    let s = switch as usize;
    assert!(steps[..s - 1].iter().all(|&d| d == batch), "{steps:?}");
    assert_eq!(steps[s - 1], reevaluations + batch, "{steps:?}");
    assert!(steps[s..].iter().all(|&d| d == batch), "{steps:?}");
}

/// `resolution.merged_population`: islands that split one population (three of 4) merge back
/// into its whole, so the finer grid re-evaluates every design the islands held (12, not
/// `search.population`'s 4), the merged island keeps all 12 and breeds the 3 x 4 children.
#[test]
fn split_islands_merge_back_into_their_whole_population() {
    let dir = scratch_dir("merge-whole");
    let sections = r#"
[search]
population = 4
islands = 3
children_per_epoch = 4
initial_points = 20
[budget]
evaluations = 204
[resolution]
levels = [[3, 9, 3], [4, 12, 4]]
stall_epochs = 1000
latest_switch = [100]
merge_islands = true
merged_population = 12
"#;
    let config = circular_arc("merge-whole", 5, &dir, sections);
    let run = run_locally(&config, 2);
    assert_eq!((run.evaluations, run.populations.len()), (204, 1));
    assert_eq!(run.populations[0].len(), 12);

    let db = rusqlite::Connection::open(config.run_dir().join("run.sqlite")).unwrap();
    let genomes = |sql: &str| -> Vec<String> {
        let mut stmt = db.prepare(sql).unwrap();
        let mut found: Vec<String> = (stmt.query_map([], |r| r.get(0)).unwrap())
            .map(Result::unwrap)
            .collect();
        found.sort();
        found
    };
    let switch: i64 = db
        .query_row(
            "SELECT MIN(epoch) FROM evaluation WHERE purpose = 'reevaluation'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    let carried = genomes("SELECT genome FROM evaluation WHERE purpose = 'reevaluation'");
    let mut held = genomes(&format!(
        "SELECT e.genome FROM population p JOIN evaluation e USING (task_id) WHERE p.epoch = {switch}"
    ));
    assert_eq!(held.len(), 12);
    held.dedup();
    // Every distinct design the three islands held is carried once; migrants' copies are the
    // only repeats, and they fill what is left of the 12.
    let mut distinct = carried.clone();
    distinct.dedup();
    assert_eq!(carried.len(), 12);
    assert_eq!(distinct, held);
    assert_one_switch(&db, switch, 12, 12);
}
