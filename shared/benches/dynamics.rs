//! Dynamics benchmarks (single thread).
//!
//! `cargo bench -p amorph --bench dynamics` runs the criterion step benchmarks: the per-pass cost
//! table on a 10³ block and the N = 10 and N = 20 speed blocks (voxel-steps/s as throughput). Extra
//! modes, selected by a free argument after `--`:
//! - `eval`: paper-style locomotion evaluations of two random 20³-workspace robots (one the size
//!   of the paper's, one the largest of 20), timed;
//! - `min`: the per-pass table and the blocks as the *minimum* time per step over many short
//!   repetitions, robust to a machine shared with other jobs (use it for before/after tables);
//! - `robot`: the per-pass table of `min` on the `eval` mode's paper-sized robot;
//! - `study`: the error-against-run-time study: CSV and a PNG plot under
//!   `$CARGO_TARGET_DIR/dynamics-study/` (or `target/dynamics-study/`).
//!
//! With `mixed` among the arguments every scene of the `min`, `robot`, `threads` and `eval` modes
//! runs the mixed-precision link kernel (`LinkPrecision::Mixed`) instead of the double one.

use std::hint::black_box;
use std::sync::OnceLock;
use std::time::Instant;

use amorph::dynamics::{DynamicScene, LinkPrecision, Pass, Simulation, foam_palette};
use amorph::genome::{GenomeLimits, random_genome};
use amorph::material::{Material, MaterialId, Palette};
use amorph::task::locomotion::{LocomotionProtocol, SettleRule, simulate_locomotion};
use amorph::voxel::{DEFAULT_THRESHOLD, GridDims, VoxelGrid, keep_largest_component, voxelize};
use criterion::{Criterion, Throughput};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The link kernel's precision for every scene of the extra modes (`mixed` among the arguments).
static PRECISION: OnceLock<LinkPrecision> = OnceLock::new();

fn precision() -> LinkPrecision {
    PRECISION.get().copied().unwrap_or_default()
}

/// The reference speed scene: an N³ block on the floor with gravity, friction 1.0/0.3, voxels with
/// x < N/2 actuated ±20 % at a 0.5 s period, s = 0.01 m, E = 1 MPa, ν = 0.35, ρ = 1000.
fn speed_block(n: usize) -> Simulation {
    speed_block_with(n, false)
}

/// [`speed_block`], optionally with the lateral Poisson coupling on.
fn speed_block_with(n: usize, poisson: bool) -> Simulation {
    let mut passive = Material::new("passive", 1.0e6, 0.35);
    passive.static_friction = 1.0;
    passive.kinetic_friction = 0.3;
    let mut active = passive.clone();
    active.actuated = true;
    let dims = GridDims::new(n, n, n);
    let mut grid = VoxelGrid::empty(dims);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                grid.set(x, y, z, Some(MaterialId(u8::from(x < n / 2))));
            }
        }
    }
    let scene = DynamicScene {
        voxel_size: 0.01,
        actuation: Some(amorph::dynamics::Actuation {
            amplitude_volume: 0.2,
            period: 0.5,
            phase: 0.0,
        }),
        poisson,
        link_precision: precision(),
        ..DynamicScene::paper_locomotion()
    };
    let mut sim = Simulation::new(&grid, &Palette(vec![passive, active]), &scene).unwrap();
    sim.start_actuation();
    // Let it land so floor contact and friction are exercised.
    sim.run_steps(200).unwrap();
    sim
}

fn bench_blocks(c: &mut Criterion) {
    let mut group = c.benchmark_group("dynamics_step");
    for n in [10, 20] {
        let mut sim = speed_block(n);
        group.throughput(Throughput::Elements((n * n * n) as u64));
        group.bench_function(format!("block_{n}x{n}x{n}_floor_friction_actuated"), |b| {
            b.iter(|| black_box(sim.step()))
        });
    }
    group.finish();
}

/// The pass sets timed one by one (criterion and the `min` table use the same list): the whole
/// scene, then each pass alone with the integration every step needs.
fn pass_cases(full: &Simulation) -> Vec<(&'static str, Vec<Pass>)> {
    let links = |damped, actuated| Pass::Links { damped, actuated };
    vec![
        ("all_passes", full.passes().to_vec()),
        ("integrate_only", vec![Pass::Integrate]),
        ("links_plain", vec![links(false, false), Pass::Integrate]),
        ("links_damped", vec![links(true, false), Pass::Integrate]),
        (
            "links_damped_actuated",
            vec![links(true, true), Pass::Integrate],
        ),
        ("gravity", vec![Pass::Gravity, Pass::Integrate]),
        ("floor_friction", vec![Pass::Floor, Pass::Integrate]),
    ]
}

fn bench_passes(c: &mut Criterion) {
    let mut group = c.benchmark_group("dynamics_pass_10x10x10");
    group.throughput(Throughput::Elements(1000));
    let full = speed_block(10);
    for (name, passes) in pass_cases(&full) {
        let mut sim = full.clone();
        sim.set_passes(passes);
        group.bench_function(name, |b| b.iter(|| black_box(sim.step())));
    }
    // Self-collision is off in the speed scene; measure it on the same block with it on.
    let mut with_collisions = speed_block_with_collisions();
    with_collisions.set_passes(vec![Pass::Collisions, Pass::Integrate]);
    group.bench_function("collisions", |b| {
        b.iter(|| black_box(with_collisions.step()))
    });
    // A scene with everything off builds exactly the plain link pass and the integration.
    let grid = VoxelGrid::filled(GridDims::new(10, 10, 10), MaterialId(0));
    let mut off = Simulation::new(
        &grid,
        &Palette(vec![Material::new("m", 1.0e6, 0.35)]),
        &DynamicScene::free_space(0.01),
    )
    .unwrap();
    assert_eq!(
        off.passes(),
        &[
            Pass::Links {
                damped: false,
                actuated: false
            },
            Pass::Integrate
        ]
    );
    group.bench_function("scene_everything_off", |b| b.iter(|| black_box(off.step())));
    group.finish();
}

/// Minimum wall time per step of `sim` over 40 repetitions of `steps` steps, µs. A step that
/// fails stops the bench: a diverged scene returns at once, and its "time" would be a lie.
fn min_step_time(sim: &mut Simulation, steps: usize) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..40 {
        let start = Instant::now();
        for _ in 0..steps {
            if let Err(e) = black_box(sim.step()) {
                panic!("a timed scene must not fail: {e}");
            }
        }
        best = best.min(start.elapsed().as_secs_f64() / steps as f64);
    }
    best * 1e6
}

/// The `min` mode: per-pass cost on the 10³ block and the N = 10 and N = 20 blocks.
fn min_table() {
    let full = speed_block(10);
    for (name, passes) in pass_cases(&full) {
        let mut sim = full.clone();
        sim.set_passes(passes);
        println!("{name:<24} {:9.1} µs", min_step_time(&mut sim, 50));
    }
    // The lateral Poisson coupling: its pass beside the links it stiffens (alone it pushes the
    // voxels apart with nothing to hold them, and the block diverges within the repetitions), and
    // the whole step with it.
    let coupled = speed_block_with(10, true);
    let links = Pass::Links {
        damped: true,
        actuated: true,
    };
    let mut sim = coupled.clone();
    sim.set_passes(vec![links, Pass::Integrate]);
    let without = min_step_time(&mut sim, 50);
    let mut sim = coupled.clone();
    sim.set_passes(vec![links, Pass::Poisson, Pass::Integrate]);
    let with = min_step_time(&mut sim, 50);
    println!(
        "{:<24} {with:9.1} µs  (the Poisson pass: {:.1} µs)",
        "links_poisson",
        with - without
    );
    let mut sim = coupled.clone();
    let t = min_step_time(&mut sim, 50);
    println!(
        "block_10 with poisson    {t:9.1} µs  {:.2e} voxel-steps/s, dt {:.3}x the uncoupled one",
        1000.0 / (t * 1e-6),
        coupled.dt() / full.dt()
    );
    for n in [10, 20] {
        let mut sim = speed_block(n);
        let t = min_step_time(&mut sim, if n == 10 { 50 } else { 10 });
        println!(
            "block_{n}{:<17} {t:9.1} µs  {:.2e} voxel-steps/s",
            "",
            (n * n * n) as f64 / (t * 1e-6)
        );
    }
}

fn speed_block_with_collisions() -> Simulation {
    let grid = VoxelGrid::filled(GridDims::new(10, 10, 10), MaterialId(0));
    let scene = DynamicScene {
        voxel_size: 0.01,
        collisions: true,
        ..DynamicScene::default()
    };
    Simulation::new(
        &grid,
        &Palette(vec![Material::new("m", 1.0e6, 0.35)]),
        &scene,
    )
    .unwrap()
}

/// A reproducible paper-style robot: 88 random Gaussian points in a 20³ workspace, two foams,
/// largest body kept.
fn paper_robot(seed: u64) -> VoxelGrid {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let genome = random_genome(&mut rng, 88, &GenomeLimits::default(), 2);
    let grid = voxelize(&genome, GridDims::new(20, 20, 20), 2, DEFAULT_THRESHOLD);
    keep_largest_component(&grid)
}

/// The `threads` mode: the N = 10 and N = 20 blocks' step on the calling thread alone, then inside
/// pools of each of `counts` threads (the same bits: `dynamics::parallel`).
fn threads_table(counts: &[usize]) {
    for n in [10, 20] {
        let steps = if n == 10 { 50 } else { 10 };
        let alone = min_step_time(&mut speed_block(n), steps);
        println!("block_{n} alone            {alone:9.1} µs");
        for &threads in counts {
            let t = in_pool(Some(threads), || min_step_time(&mut speed_block(n), steps));
            println!(
                "block_{n} {threads:>2} threads       {t:9.1} µs  {:.2}x alone",
                alone / t
            );
        }
    }
}

/// `f` on the calling thread, or inside a pool of `threads` threads.
fn in_pool<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads {
        None => f(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("a thread pool")
            .install(f),
    }
}

/// The `eval` mode's two robots of the 20 seeds: the one closest in size to the paper's
/// 3,544-voxel robot, and the largest.
fn eval_robots() -> (VoxelGrid, VoxelGrid) {
    let robots: Vec<VoxelGrid> = (0..20).map(paper_robot).collect();
    let paper_sized = robots
        .iter()
        .min_by_key(|g| g.filled_count().abs_diff(3544))
        .unwrap();
    let largest = robots.iter().max_by_key(|g| g.filled_count()).unwrap();
    (paper_sized.clone(), largest.clone())
}

/// The `robot` mode: the `min` table's passes on the `eval` mode's paper-sized robot, actuated
/// on the floor after 2,000 steps, so that each pass is priced on the body the 20³ evaluation
/// target is about (its fill, its runs of consecutive voxels) and not on a full block.
fn robot_table() {
    let scene = DynamicScene {
        link_precision: precision(),
        ..DynamicScene::paper_locomotion()
    };
    let mut full = Simulation::new(&eval_robots().0, &foam_palette(), &scene).unwrap();
    full.start_actuation();
    full.run_steps(2000).unwrap();
    let (voxels, links) = (full.voxel_count(), full.link_count());
    println!(
        "paper-sized robot: {voxels} voxels, {links} links, {:?} kernel",
        precision()
    );
    for (name, passes) in pass_cases(&full) {
        let mut sim = full.clone();
        sim.set_passes(passes);
        let t = min_step_time(&mut sim, 20);
        println!(
            "{name:<24} {t:9.1} µs  {:6.1} ns/voxel  {:6.1} ns/link",
            t * 1e3 / voxels as f64,
            t * 1e3 / links as f64
        );
    }
}

/// The `eval` mode: paper-style evaluations of two random robots from 20 seeds, the one closest
/// in size to the paper's 3,544-voxel robot (the reference engine's 178 s) and the largest; with
/// `--threads N` each runs inside a pool of N threads; `only` picks one of the two by name.
fn paper_evaluation(threads: Option<usize>, only: Option<&str>) {
    let (paper_sized, largest) = eval_robots();
    for (name, grid) in [("paper-sized", &paper_sized), ("largest", &largest)] {
        if only.is_some_and(|o| o != name) {
            continue;
        }
        let scene = DynamicScene {
            link_precision: precision(),
            ..DynamicScene::paper_locomotion()
        };
        let start = Instant::now();
        let protocol = LocomotionProtocol::default();
        let outcome = in_pool(threads, || {
            simulate_locomotion(grid, &foam_palette(), &scene, &protocol)
        });
        let wall = start.elapsed().as_secs_f64();
        println!(
            "paper-style evaluation ({} threads, {:?} kernel), {name} robot: {} voxels, {} steps ({:.3} s simulated, settled \
             after {:.3} s, dt {:.3e} s), {:.1} s wall, {:.3e} voxel-steps/s, status {:?}, \
             gait {:.3} %/cycle (bits {:016x})",
            threads.map_or("alone".to_string(), |n| n.to_string()),
            precision(),
            outcome.voxel_count,
            outcome.steps,
            outcome.simulated_time,
            outcome.settle_time,
            outcome.dt,
            wall,
            outcome.voxel_count as f64 * outcome.steps as f64 / wall,
            outcome.status,
            outcome.speed_percent_per_cycle,
            outcome.fitness.to_bits()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "mixed") {
        PRECISION.set(LinkPrecision::Mixed).ok();
    }
    if args.iter().any(|a| a == "study") {
        study();
        return;
    }
    if args.iter().any(|a| a == "min") {
        min_table();
        return;
    }
    if args.iter().any(|a| a == "robot") {
        robot_table();
        return;
    }
    let numbers =
        |from: usize| -> Vec<usize> { args[from..].iter().map_while(|a| a.parse().ok()).collect() };
    if let Some(i) = args.iter().position(|a| a == "threads") {
        let counts = numbers(i + 1);
        threads_table(if counts.is_empty() { &[1, 2] } else { &counts });
        return;
    }
    if args.iter().any(|a| a == "eval") {
        let threads = args
            .iter()
            .position(|a| a == "--threads")
            .and_then(|i| numbers(i + 1).first().copied());
        let only = ["paper-sized", "largest"]
            .into_iter()
            .find(|name| args.iter().any(|a| a == name));
        paper_evaluation(threads, only);
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    bench_passes(&mut c);
    bench_blocks(&mut c);
    c.final_summary();
}

/// One run of the study: its parameters, the error and the wall time.
struct StudyPoint {
    case: &'static str,
    resolution: usize,
    dt_fraction: f64,
    steps: u64,
    wall: f64,
    value: f64,
    error: f64,
}

/// Static tip deflection of the 2r×20r×2r cantilever (the 2×2×20 test beam at r times the
/// resolution), settled with near-critical global damping, against F L³/(3EI).
fn cantilever_run(r: usize, dt_fraction: f64) -> StudyPoint {
    let s = 0.01 / r as f64;
    let mut m = Material::new("rubber", 1.0e6, 0.35);
    m.density = 1000.0;
    let grid = VoxelGrid::filled(GridDims::new(2 * r, 20 * r, 2 * r), MaterialId(0));
    let scene = DynamicScene {
        dt_fraction,
        damping: amorph::dynamics::DampingParams {
            link: 1.0,
            global: 0.005 / r as f64,
            contact: 0.0,
        },
        ..DynamicScene::free_space(s)
    };
    let mut sim = Simulation::new(&grid, &Palette(vec![m]), &scene).unwrap();
    let mut tip = Vec::new();
    for z in 0..2 * r {
        for x in 0..2 * r {
            sim.fix_voxel(sim.voxel_at([x, 0, z]).unwrap()).unwrap();
            tip.push(sim.voxel_at([x, 20 * r - 1, z]).unwrap());
        }
    }
    let per_voxel = 0.01 / tip.len() as f64;
    for &i in &tip {
        sim.add_external_force(i, amorph::dynamics::Vec3::new(0.0, 0.0, -per_voxel))
            .unwrap();
    }
    let start = Instant::now();
    let result = sim.run_for(3.0);
    let wall = start.elapsed().as_secs_f64();
    let z = tip.iter().map(|&i| sim.positions()[i].z).sum::<f64>() / tip.len() as f64;
    let deflection = 0.01 - z;
    let span = 0.2 - s;
    let analytic = 0.01 * span.powi(3) / (3.0 * 1.0e6 * 0.02_f64.powi(4) / 12.0);
    StudyPoint {
        case: "cantilever",
        resolution: r,
        dt_fraction,
        steps: sim.steps(),
        wall,
        value: deflection,
        error: if result.is_ok() {
            (deflection / analytic - 1.0).abs()
        } else {
            f64::NAN
        },
    }
}

/// Locomotion of one robot (seed 7) at `r` voxels across the 20 mm workspace, 3 cycles.
fn locomotion_run(r: usize, dt_fraction: f64) -> StudyPoint {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let genome = random_genome(&mut rng, 88, &GenomeLimits::default(), 2);
    let grid = voxelize(&genome, GridDims::new(r, r, r), 2, DEFAULT_THRESHOLD);
    let scene = DynamicScene {
        voxel_size: 0.02 / r as f64,
        dt_fraction,
        ..DynamicScene::paper_locomotion()
    };
    let protocol = LocomotionProtocol {
        actuation_cycles: 3,
        settle: SettleRule {
            max_time: 0.1,
            still_speed: 0.0,
            check_interval: 0.01,
            damping: None,
        },
        ..LocomotionProtocol::default()
    };
    let start = Instant::now();
    let outcome = simulate_locomotion(&grid, &foam_palette(), &scene, &protocol);
    let wall = start.elapsed().as_secs_f64();
    StudyPoint {
        case: "locomotion",
        resolution: r,
        dt_fraction,
        steps: outcome.steps,
        wall,
        value: outcome.completed_fitness().unwrap_or(f64::NAN),
        error: f64::NAN,
    }
}

fn study() {
    let dir = std::path::PathBuf::from(
        std::env::var("CARGO_TARGET_DIR")
            .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../target").into()),
    )
    .join("dynamics-study");
    std::fs::create_dir_all(&dir).unwrap();
    let fractions = [0.25, 0.5, 1.0, 2.0];
    let mut points = Vec::new();
    for r in [1, 2] {
        for &f in &fractions {
            let p = cantilever_run(r, f);
            println!(
                "cantilever r={r} f={f}: error {:.3e}, {:.2} s",
                p.error, p.wall
            );
            points.push(p);
        }
    }
    let mut loco = Vec::new();
    for r in [10, 20] {
        for &f in &fractions {
            let p = locomotion_run(r, f);
            println!(
                "locomotion r={r} f={f}: Δx {:.4e} m, {:.2} s",
                p.value, p.wall
            );
            loco.push(p);
        }
    }
    // Error against the finest run (highest resolution, smallest step).
    let finest = loco
        .iter()
        .filter(|p| p.resolution == 20)
        .min_by(|a, b| a.dt_fraction.total_cmp(&b.dt_fraction))
        .map(|p| p.value)
        .unwrap();
    for p in &mut loco {
        p.error = (p.value - finest).abs() / finest.abs();
    }
    points.extend(loco);
    let mut csv = String::from("case,resolution,dt_fraction,steps,wall_s,value,relative_error\n");
    for p in &points {
        csv.push_str(&format!(
            "{},{},{},{},{:.4},{:.6e},{:.4e}\n",
            p.case, p.resolution, p.dt_fraction, p.steps, p.wall, p.value, p.error
        ));
    }
    std::fs::write(dir.join("error_vs_time.csv"), csv).unwrap();
    std::fs::write(dir.join("error_vs_time.png"), study_png(&points)).unwrap();
    println!("wrote {}", dir.display());
}

/// A log–log plot of relative error against wall time, one line per case and resolution (points
/// along a line are the time-step fractions), as PNG through the library's own plotter.
fn study_png(points: &[StudyPoint]) -> Vec<u8> {
    use amorph::report::{PlotSpec, Series, line_plot};
    let colours = [
        [31, 119, 180],
        [214, 39, 40],
        [44, 160, 44],
        [148, 103, 189],
    ];
    let mut keys: Vec<(&str, usize)> = points.iter().map(|p| (p.case, p.resolution)).collect();
    keys.dedup();
    let series: Vec<Series> = keys
        .iter()
        .enumerate()
        .map(|(i, &(case, r))| {
            let mut pts: Vec<[f64; 2]> = points
                .iter()
                .filter(|p| p.case == case && p.resolution == r)
                .map(|p| [p.wall, p.error])
                .collect();
            pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
            Series {
                label: format!("{case} r={r}"),
                colour: colours[i % colours.len()],
                markers: true,
                points: pts,
            }
        })
        .collect();
    let spec = PlotSpec {
        title: "ERROR AGAINST RUN TIME (DT FRACTION 0.25 TO 2)".into(),
        x_label: "WALL TIME (S), ONE THREAD".into(),
        y_label: "RELATIVE ERROR".into(),
        log_x: true,
        log_y: true,
    };
    line_plot(&spec, &series).to_png().expect("PNG encoding")
}
