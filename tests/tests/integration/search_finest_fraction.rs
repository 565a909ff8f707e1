//! `search.local_search.finest_fraction` gives the finest resolution level its own share
//! of nudges. The coarse level must breed exactly as without the key, and at the finest level, with
//! a share of 1, every child must be a nudge of the run's best: that design with one point moved
//! or one point appended, never a crossover child.

use amorph::genome::Genome;
use amorph_coordinator::RunConfig;
use amorph_tests::{
    fingerprint, resume_locally, run_locally, scratch_dir, test_config, thread_count_blind,
};
use rusqlite::Connection;
use std::path::Path;

/// Three islands on two levels sharing one climb (with insertions, no combination, so that
/// every nudge is one move of the best), switching by `latest_switch` at 100 evaluations.
fn config(results_dir: &Path, finest: Option<f64>, evaluations: u64) -> RunConfig {
    let evaluations = format!("budget.evaluations={evaluations}");
    let mut sets = vec![
        "name=finest-fraction",
        "seed=5",
        "search.population=6",
        "search.islands=3",
        "search.children_per_epoch=6",
        "search.initial_points=12",
        "search.local_search.fraction=0.5",
        "search.local_search.step=0.02",
        "search.local_search.insertion=0.3",
        "search.local_search.shared=true",
        &evaluations,
        "resolution.levels=[[3, 9, 3], [4, 12, 4]]",
        "resolution.stall_epochs=1000",
        "resolution.latest_switch=[100]",
    ];
    let finest = finest.map(|f| format!("search.local_search.finest_fraction={f}"));
    sets.extend(finest.as_deref());
    test_config("circular_arc", results_dir, &sets)
}

/// `(epoch, purpose, genome, outcome)` of an evaluation.
type Row = (i64, String, String, String);

/// Every evaluation, in task order.
fn evaluations(db: &Connection) -> Vec<Row> {
    let mut stmt = db
        .prepare("SELECT epoch, purpose, genome, outcome FROM evaluation ORDER BY task_id")
        .unwrap();
    stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// The run's best genome after `epoch`: the fittest stored population member, the lowest island
/// and then the lowest slot on a tie (the island that holds the shared climb's design).
fn run_best(db: &Connection, epoch: i64) -> Genome {
    let genome: String = db
        .query_row(
            "SELECT e.genome FROM population p JOIN evaluation e USING (task_id)
             WHERE p.epoch = ?1 AND p.fitness IS NOT NULL
             ORDER BY p.fitness DESC, p.island, p.slot LIMIT 1",
            [epoch],
            |r| r.get(0),
        )
        .unwrap();
    serde_json::from_str(&genome).unwrap()
}

/// Whether `child` is `best` with at most one point moved (material kept) or with one point
/// appended: what a nudge or an insertion makes.
fn is_a_step_from(best: &Genome, child: &Genome) -> bool {
    let (b, c) = (&best.points, &child.points);
    if c.len() == b.len() + 1 {
        return c[..b.len()] == b[..];
    }
    c.len() == b.len()
        && b.iter().zip(c).all(|(p, q)| p.material == q.material)
        && b.iter().zip(c).filter(|(p, q)| p != q).count() <= 1
}

/// Children of the finest level after its first epoch (`rows` are `db`'s evaluations) as (is a
/// step from the run's best before their epoch) flags.
fn finest_children_are_steps(db: &Connection, rows: &[Row], switch: i64) -> Vec<bool> {
    (rows.iter())
        .filter(|(epoch, purpose, _, _)| purpose == "child" && *epoch > switch + 1)
        .map(|(epoch, _, genome, _)| {
            let child: Genome = serde_json::from_str(genome).unwrap();
            is_a_step_from(&run_best(db, epoch - 1), &child)
        })
        .collect()
}

#[test]
fn a_finest_fraction_of_one_breeds_only_nudges_there_and_leaves_the_coarse_level_alone() {
    let (keyed, keyed_config) =
        thread_count_blind("finest-fraction", |dir| config(dir, Some(1.0), 220));
    assert_eq!(keyed.evaluations, 220);
    let plain_config = config(&scratch_dir("finest-fraction-plain"), None, 220);
    run_locally(&plain_config, 2);
    let open = |c: &RunConfig| Connection::open(c.run_dir().join("run.sqlite")).unwrap();
    let (keyed_db, plain_db) = (open(&keyed_config), open(&plain_config));

    // The coarse level, and the re-evaluation that ends it (stored with the last coarse epoch's
    // number; the finest level's children start at the next), are the plain run's to the bit.
    let (keyed_rows, plain_rows) = (evaluations(&keyed_db), evaluations(&plain_db));
    let switch = keyed_rows
        .iter()
        .find(|r| r.1 == "reevaluation")
        .expect("the run switched")
        .0;
    let upto =
        |rows: &[Row]| -> Vec<Row> { rows.iter().filter(|r| r.0 <= switch).cloned().collect() };
    assert_eq!(upto(&keyed_rows), upto(&plain_rows));
    assert!(keyed_rows != plain_rows, "the key changed nothing");

    // At the finest level every child of the keyed run is one step from the run's best; the plain
    // run breeds half its children by crossover, and most of those are not.
    let keyed_steps = finest_children_are_steps(&keyed_db, &keyed_rows, switch);
    let plain_steps = finest_children_are_steps(&plain_db, &plain_rows, switch);
    assert!(
        keyed_steps.len() >= 60,
        "{} finest children",
        keyed_steps.len()
    );
    assert!(keyed_steps.iter().all(|&s| s), "{keyed_steps:?}");
    let crossed = plain_steps.iter().filter(|&&s| !s).count();
    assert!(crossed * 4 >= plain_steps.len(), "{plain_steps:?}");

    // Stopped at the end of the finest level's second epoch (the switch re-evaluates 18 at 108,
    // then epochs of 18) and resumed: the same bits, the finest share restored on the replay.
    let dir = scratch_dir("finest-fraction-resumed");
    let stopped = run_locally(&config(&dir, Some(1.0), 162), 1);
    assert_eq!(stopped.evaluations, 162);
    let resumed = resume_locally(&config(&dir, Some(1.0), 220), 3);
    assert!(
        fingerprint(&resumed) == fingerprint(&keyed),
        "the resumed run differs"
    );
}
