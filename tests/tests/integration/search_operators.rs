//! The search's operators beyond the paper's crossover (nudges of the best, boundary insertions,
//! the shared climb and its combinations, migration into the most similar slot) keep a run
//! bit-identical whatever the number of evaluation threads and across a resume, and never lose
//! an island's best; `diversity.csv` records every island after every epoch.

use amorph::genome::Genome;
use amorph_coordinator::RunConfig;
use amorph_tests::{fingerprint, resume_locally, run_locally, scratch_dir, test_config};
use std::path::Path;

/// Three islands on the circular arc's paper search with nudges of the best and ring migration into
/// the most similar slot; `local_search` adds its keys (`--set` style).
fn config(results_dir: &Path, seed: u64, local_search: &[&str]) -> RunConfig {
    let seed = format!("seed={seed}");
    let mut sets = vec![
        "name=operators",
        &seed,
        "search.population=10",
        "search.islands=3",
        "search.children_per_epoch=10",
        "search.initial_points=20",
        "search.migration.interval=2",
        "search.migration.topology={ kind = \"ring\" }",
        "search.migration.replacement=most_similar",
        "search.local_search.fraction=0.3",
        "search.local_search.step=0.02",
        "budget.evaluations=240",
        "resolution.levels=[[4, 12, 4]]",
    ];
    sets.extend(local_search);
    test_config("circular_arc", results_dir, &sets)
}

/// The shared, combined climb with insertions.
const CLIMB: [&str; 3] = [
    "search.local_search.insertion=0.5",
    "search.local_search.shared=true",
    "search.local_search.combine=true",
];

/// One climb fed by every island (`shared`, with insertions, the improving nudges of each epoch
/// combined into one child of the next): the nudges of three islands go to the one holding the
/// run's best, and the run stays bit-identical whatever the thread count, its best never worse
/// from one epoch to the next.
#[test]
fn a_shared_climb_is_bit_identical_on_1_and_3_threads_and_never_loses_the_best() {
    let dirs = [scratch_dir("shared-1"), scratch_dir("shared-3")];
    let configs = dirs.each_ref().map(|d| config(d, 7, &CLIMB));
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

/// The shared, combined climb with insertions (most children nudges of the best, so that epochs
/// have several nudges to add up) is bit-identical on 1 and 3 threads and when stopped at an
/// epoch's end and resumed: the combination offered after the stop is rebuilt from the replayed
/// epoch.
#[test]
fn a_combined_climb_resumes_bit_identical() {
    let config = |dir: &Path| {
        let mut config = config(dir, 7, &CLIMB);
        config.search.local_search.fraction = 0.8;
        config
    };
    let one = fingerprint(&run_locally(&config(&scratch_dir("climb-1")), 1));
    let three = fingerprint(&run_locally(&config(&scratch_dir("climb-3")), 3));
    assert!(one == three, "1 and 3 threads differ");
    // Stopped at the end of an epoch (30 initial + 3 epochs of 30) and resumed to 240.
    let dir = scratch_dir("climb-resumed");
    let mut stopped = config(&dir);
    stopped.budget.evaluations = Some(120);
    assert_eq!(run_locally(&stopped, 2).evaluations, 120);
    let resumed = resume_locally(&config(&dir), 3);
    assert!(fingerprint(&resumed) == one, "the resumed run differs");
}

#[test]
fn operators_are_bit_identical_on_1_and_3_threads_and_never_lose_an_islands_best() {
    let dirs = [scratch_dir("operators-1"), scratch_dir("operators-3")];
    let configs = dirs.each_ref().map(|d| config(d, 5, &[]));
    let one = run_locally(&configs[0], 1);
    let three = run_locally(&configs[1], 3);
    assert_eq!(one.evaluations, 240);
    assert_eq!(one.populations, three.populations);

    let limits = *configs[0].scene.limits();
    let materials = configs[0].scene.palette().len();
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

    // diversity.csv: a row per island per epoch; within-island distances are finite and
    // non-negative.
    let text = std::fs::read_to_string(configs[0].run_dir().join("diversity.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 3 * one.epochs);
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
