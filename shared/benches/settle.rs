//! The settling study: how much a damped settle shortens a locomotion evaluation, and how much it
//! moves the fitness, against how much halving the time step moves it.
//!
//! `cargo bench -p amorph --bench settle -- N [ROBOTS [ZETA]]` evaluates ROBOTS (default 20) random
//! 88-point robots in an N³ workspace (1 mm voxels at N = 20, as the paper; 2 mm at N = 10, as
//! `configs/locomotion.toml`) three ways, single thread:
//! - `reference`: the scene's own damping while settling (`settle.damping` unset, the
//!   paper's protocol);
//! - `settled`: `settle.damping` = ZETA (default 0.1);
//! - `half_step`: the reference at half the time step, the yardstick for what a change of
//!   fitness means (a walking gait is a chaotic contact problem).
//!
//! and prints one CSV row per robot and evaluation, then the medians and maxima of the relative
//! changes and the ratio of steps and wall time.
//!
//! `cargo bench -p amorph --bench settle -- step N ROBOTS LINK_ZETA DT_FRACTION` compares a longer
//! step instead: the candidate (`settled` in the output) is the reference with the link damping
//! ratio LINK_ZETA and the time-step fraction DT_FRACTION (the explicit link damping bounds the
//! step: docs/explanation/physics.md). `FIRST_SEED=k` starts the robots at seed k (seed 13
//! at 10³ is the one random robot that walks, ~10 mm in 10 cycles).
//!
//! `cargo bench -p amorph --bench settle -- mixed N ROBOTS` compares the mixed-precision link
//! kernel instead: the candidate is the reference with `LinkPrecision::Mixed`.

use std::time::Instant;

use amorph::dynamics::{DynamicScene, LinkPrecision, foam_palette};
use amorph::genome::{GenomeLimits, random_genome};
use amorph::task::locomotion::{LocomotionOutcome, LocomotionProtocol, simulate_locomotion};
use amorph::voxel::{DEFAULT_THRESHOLD, GridDims, VoxelGrid, keep_largest_component, voxelize};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn robot(seed: u64, n: usize) -> VoxelGrid {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let genome = random_genome(&mut rng, 88, &GenomeLimits::default(), 2);
    let grid = voxelize(&genome, GridDims::new(n, n, n), 2, DEFAULT_THRESHOLD);
    keep_largest_component(&grid)
}

/// One way of evaluating: its name, settle damping, link damping ratio, time-step fraction and
/// link kernel.
type Case = (&'static str, Option<f64>, f64, f64, LinkPrecision);

fn evaluate(grid: &VoxelGrid, n: usize, case: Case) -> (LocomotionOutcome, f64) {
    let (_, settle_damping, link_zeta, dt_fraction, link_precision) = case;
    let mut scene = DynamicScene::paper_locomotion();
    scene.link_precision = link_precision;
    scene.voxel_size = 0.02 / n as f64;
    scene.dt_fraction = dt_fraction;
    scene.damping.link = link_zeta;
    let mut protocol = LocomotionProtocol::default();
    protocol.settle.damping = settle_damping;
    let start = Instant::now();
    let outcome = simulate_locomotion(grid, &foam_palette(), &scene, &protocol);
    (outcome, start.elapsed().as_secs_f64())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

fn main() {
    let step_mode = std::env::args().any(|a| a == "step");
    let mixed_mode = std::env::args().any(|a| a == "mixed");
    let double = LinkPrecision::Double;
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let n = args.first().map_or(10, |&a| a as usize);
    let robots = args.get(1).map_or(20, |&a| a as u64);
    let zeta = args.get(2).copied().unwrap_or(0.1);
    let reference_link = amorph::dynamics::DampingParams::default().link;
    let candidate: Case = if mixed_mode {
        ("settled", None, reference_link, 1.0, LinkPrecision::Mixed)
    } else if step_mode {
        let dt_fraction = args.get(3).copied().unwrap_or(1.0);
        ("settled", None, zeta, dt_fraction, double)
    } else {
        ("settled", Some(zeta), reference_link, 1.0, double)
    };
    let describe = if mixed_mode {
        "the mixed-precision link kernel".to_string()
    } else if step_mode {
        format!(
            "link damping {} at dt_fraction {}",
            candidate.2, candidate.3
        )
    } else {
        format!("settle.damping {zeta}")
    };
    println!(
        "seed,voxels,case,fitness_mm,speed_percent_per_cycle,settle_time_s,steps,wall_s,status"
    );
    let (mut settled_change, mut half_change) = (Vec::new(), Vec::new());
    let (mut steps, mut wall) = ([0u64; 2], [0.0f64; 2]);
    // FIRST_SEED skips to one robot of the list (e.g. the one that walks).
    let first: u64 = std::env::var("FIRST_SEED").map_or(0, |s| s.parse().unwrap_or(0));
    for seed in first..first + robots {
        let grid = robot(seed, n);
        let cases: [Case; 3] = [
            ("reference", None, reference_link, 1.0, double),
            candidate,
            ("half_step", None, reference_link, 0.5, double),
        ];
        let mut fitness = Vec::new();
        for (k, case) in cases.into_iter().enumerate() {
            let name = case.0;
            let (o, w) = evaluate(&grid, n, case);
            println!(
                "{seed},{},{name},{:.6},{:.4},{:.4},{},{w:.2},{:?}",
                o.voxel_count,
                o.fitness * 1e3,
                o.speed_percent_per_cycle,
                o.settle_time,
                o.steps,
                o.status
            );
            if k < 2 {
                steps[k] += o.steps;
                wall[k] += w;
            }
            fitness.push((o.fitness, o.body_length));
        }
        // Relative to the reference gait, or to 1 % of the body length for a robot that barely
        // moves (a relative change of nothing is not a measure of anything).
        let (reference, body) = fitness[0];
        let scale = reference.abs().max(0.01 * body);
        settled_change.push((fitness[1].0 - reference).abs() / scale);
        half_change.push((fitness[2].0 - reference).abs() / scale);
    }
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    println!(
        "# {robots} robots at {n}^3, {describe}: |settled - reference| / reference: median {:.3}, max {:.3}; \
         |half step - reference| / reference: median {:.3}, max {:.3}",
        median(settled_change.clone()),
        max(&settled_change),
        median(half_change.clone()),
        max(&half_change)
    );
    println!(
        "# steps settled / reference {:.3} ({} / {}); wall {:.3} ({:.1} s / {:.1} s)",
        steps[1] as f64 / steps[0] as f64,
        steps[1],
        steps[0],
        wall[1] / wall[0],
        wall[1],
        wall[0]
    );
}
