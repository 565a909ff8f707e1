//! How far the flip model's greedy sequence goes (issue 13, session 45; figures in
//! docs/evolution.md): the model-step children of one design, each evaluated.
//!
//! `cargo bench -p amorph-coordinator --bench model_sequence -- <design.json> <config.toml>
//! [<children>]`: builds the boundary site of the design in `design.json` (a `best_genome.json`
//! or a test fixture: genome and resolution) under the scene of `config.toml`, with the flip
//! model's sequence of at most 2^(children − 1) changes (`children` at most 8, the default), and
//! evaluates the children `local_search.model_steps` would breed from it: the design with its
//! sequence's first 1, 2, 4, ... changes. Prints the design's figure (RMS error for a beam), the
//! sequence's length, and each child's figure. Deterministic: the sequence is a function of the
//! design alone.

#[path = "common/design.rs"]
mod design;

use amorph::task::Outcome;
use amorph_coordinator::search::{InsertionBy, LocalSearchParams, MAX_MODEL_STEPS};

fn main() {
    let args = design::arguments(2, "model_sequence <design.json> <config.toml> [<children>]");
    let (genome, dims, config) = design::load(&args[0], &args[1]);
    let scene = &config.raw.scene;
    let children: usize = args.get(2).map_or(MAX_MODEL_STEPS, |c| {
        c.parse().expect("a number of children")
    });
    assert!(
        (1..=MAX_MODEL_STEPS).contains(&children),
        "children: 1 to {MAX_MODEL_STEPS}"
    );
    let figure = |o: &Outcome| scene.figure(o).unwrap_or(f64::NAN);
    let start = scene.evaluate(&genome, dims);
    // The site the run builds for the best, so the bench follows the run's rule for the limit.
    let local = LocalSearchParams {
        insertion: 1.0,
        insertion_by: InsertionBy::FlipModel,
        model_steps: children,
        ..Default::default()
    };
    let site = (local.boundary_site(&genome, &start, scene, dims)).expect("insertion is on");
    let steps = site.model_step_children(&genome, scene, children);
    println!(
        "design {:.4}; {} children from a sequence of at most {} changes",
        figure(&start),
        steps.len(),
        1 << (children - 1)
    );
    for (k, child) in steps.iter().enumerate() {
        println!(
            "{:>4} changes: {:.4}",
            1 << k,
            figure(&scene.evaluate(child, dims))
        );
    }
}
