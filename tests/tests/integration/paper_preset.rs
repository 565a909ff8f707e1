//! The paper's search stays one line away: `configs/circular_arc.toml` with `search.preset =
//! "paper"` is, bit for bit, the run the paper's configuration gives, without the local climb. The
//! fixture is that run's first 600 evaluations (seed 1, one island of 50, 6x20x6), recorded by a
//! build whose default search was the paper's, so the preset is checked against a run it did not
//! make.

use std::path::Path;

use amorph_coordinator::RunConfig;
use amorph_coordinator::config::Override;
use amorph_tests::{run_locally, scratch_dir};

fn fixture(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/paper_circular_arc")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// history.csv without its wall-time column, the one figure that depends on the machine.
fn without_wall_time(history: &str) -> String {
    (history.lines())
        .map(|line| {
            let mut fields: Vec<&str> = line.split(',').collect();
            fields.remove(2);
            fields.join(",") + "\n"
        })
        .collect()
}

#[test]
fn the_paper_preset_reproduces_the_papers_search_bit_for_bit() {
    let dir = scratch_dir("paper-preset");
    let sets: Vec<Override> = [
        "search.preset=paper".to_owned(),
        "budget.evaluations=600".to_owned(),
        format!("results_dir={:?}", dir.display().to_string()),
    ]
    .iter()
    .map(|s| s.parse().unwrap())
    .collect();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/circular_arc.toml");
    let config = RunConfig::load_with(&path, &sets).unwrap();
    assert_eq!(run_locally(&config, 2).evaluations, 600);
    let run = config.run_dir();
    let history = std::fs::read_to_string(run.join("history.csv")).unwrap();
    assert!(
        without_wall_time(&history) == fixture("history.csv"),
        "history differs:\n{history}"
    );
    let best = std::fs::read_to_string(run.join("best_genome.json")).unwrap();
    assert!(
        best == fixture("best_genome.json"),
        "the best genome differs"
    );
}
