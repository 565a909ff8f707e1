//! The island curve of issue 13 from its recorded runs: evaluations to the paper's Table III value
//! against the number of islands, per target, at an equal total (islands × population = 48 and a
//! batch of 48; docs/evolution.md, sessions 21–27).
//!
//! `cargo bench -p amorph-coordinator --bench island_curve -- $PWD/docs/data/island_curve.csv
//! $PWD/docs/img/island_curve.png` (a bench runs in its package's folder, hence the absolute paths)
//!
//! The CSV holds one row per run, `target,islands,population,seed,evaluations,session`, where
//! `evaluations` is the count at which the run first reached the paper's value, or `>N` for a run
//! stopped short after N. Prints one Markdown row per target and island count (runs, of them
//! stopped, median, quartiles, P: the probability that a run of that count reaches the paper's
//! value before a one-island run, ties counting half, and the median's ratio to one island's with
//! its 90 % bootstrap interval), then one row per island count with P averaged over the targets,
//! and draws the ratios, one line per target, with their intervals as bars.
//!
//! A stopped run is censored (`amorph_coordinator::study`): medians and quartiles are read off the
//! Kaplan–Meier estimate, "beyond" where they fall past the last finished run, and P counts the
//! order of two runs only as far as the data fix it. Until session 33 a stopped run counted as
//! later than every finished one, which overstated a run a lease had cut short early.
//!
//! One island is every one-island run of the target, population 48 and 50 together: the same
//! search from two more or fewer random designs (session 26 found the two samples' medians
//! 1.8–2.3 times apart, both ways, so neither alone is the baseline).
//!
//! The interval answers how far a median ratio could move with other seeds: both samples are
//! redrawn with replacement ([`RESAMPLES`] times, from a fixed seed, so the table is reproducible
//! to the byte), and the 5th and 95th percentiles of the redrawn ratios bound it. Each cell draws
//! from its own random stream, named by its target and island count ([`cell_rng`]), so its
//! interval moves only when its own runs or its target's one-island runs change, not when another
//! cell gains rows. A percentile bootstrap of a median is coarse for a handful of runs (with three
//! runs it can only take the runs' own values), which is the point: it shows which verdicts three
//! or seven seeds can carry.

use std::collections::BTreeMap;

use amorph::export::{PlotSpec, Series, line_plot_over};
use amorph_coordinator::study::{Reach, Survival, bootstrap_interval, faster, parse_runs};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Redraws per interval. A redrawn median can take only a few values for a handful of runs, so
/// an interval's ends jump between them with the bootstrap's own seed, and more redraws do not
/// smooth that: in session 28, with one stream for the whole table, seeds 13 and 14 gave ends up
/// to 0.05 apart (the upper end for eight islands on the straight: 0.89 and 0.94), and the
/// streams per cell moved ends by up to 0.04 (0.09 for cells of three runs); read an end to a
/// tenth.
const RESAMPLES: usize = 10_000;

/// Intervals drawn above this ratio are cut there (a stopped run's ratio is unbounded).
const BAR_CEILING: f64 = 2.5;

/// The bootstrap's random stream for one cell of the table: the same seed for every cell, and a
/// stream number hashed (FNV-1a) from the target's name and the island count, so that a cell's
/// draws do not depend on which cells come before it.
fn cell_rng(target: &str, islands: u32) -> ChaCha8Rng {
    let stream = target
        .bytes()
        .chain(islands.to_le_bytes())
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        });
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    rng.set_stream(stream);
    rng
}

/// median(a) / median(b), infinite where `a`'s median lies beyond its stopped runs.
fn median_ratio(a: &[Reach], b: &[Reach]) -> f64 {
    let median = |s: &[Reach]| Survival::new(s).median().unwrap_or(f64::INFINITY);
    median(a) / median(b)
}

/// One target's runs with an island count, beside its one-island runs.
struct Cell<'a> {
    runs: &'a [Reach],
    one: &'a [Reach],
}

/// The pooled row for one island count: P(faster) averaged over the targets, with its 90 %
/// bootstrap interval (every target's cell and baseline redrawn together). Each target weighs the
/// same, whatever its number of runs: the question is whether a user who picks that island count
/// loses on the targets they may meet. No pooled median ratio: a target whose one-island median
/// can fall beyond its stopped runs (the slope's) makes any mean of ratios run to 0 or infinity.
fn pooled(cells: &[Cell], islands: u32) -> String {
    let samples: Vec<&[Reach]> = cells.iter().flat_map(|c| [c.runs, c.one]).collect();
    let mean_p = |s: &[Vec<Reach>]| {
        s.chunks(2)
            .map(|pair| faster(&Survival::new(&pair[0]), &Survival::new(&pair[1])))
            .sum::<f64>()
            / cells.len() as f64
    };
    let owned: Vec<Vec<Reach>> = samples.iter().map(|s| s.to_vec()).collect();
    let [lo, hi] = bootstrap_interval(
        &samples,
        RESAMPLES,
        &mut cell_rng("pooled P", islands),
        mean_p,
    );
    format!(
        "| {islands} | {} | {} | {:.2} ({lo:.2}–{hi:.2}) |",
        cells.len(),
        cells.iter().map(|c| c.runs.len()).sum::<usize>(),
        mean_p(&owned),
    )
}

const COLOURS: [[u8; 3]; 4] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
];

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let Some(csv) = args.first() else {
        eprintln!("island_curve: usage: <runs.csv> [<curve.png>]");
        std::process::exit(2);
    };
    let runs = std::fs::read_to_string(csv)
        .map_err(|e| format!("{csv}: {e}"))
        .and_then(|text| parse_runs(csv, &text))
        .unwrap_or_else(|e| {
            eprintln!("island_curve: {e}");
            std::process::exit(2);
        });
    let mut by_target: BTreeMap<&str, BTreeMap<u32, Vec<Reach>>> = BTreeMap::new();
    for run in &runs {
        by_target
            .entry(&run.target)
            .or_default()
            .entry(run.islands)
            .or_default()
            .push(run.reach);
    }
    let show = |v: Option<f64>| v.map_or("beyond".to_string(), |v| format!("{v:.0}"));
    let show_ratio = |v: Option<f64>| v.map_or("beyond".to_string(), |v| format!("{v:.2}"));
    println!(
        "| target | islands | runs | stopped | median | quartiles | P(faster than one island) | median ÷ one island's (90 % interval) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let (mut series, mut bars) = (Vec::new(), Vec::new());
    let mut by_islands: BTreeMap<u32, Vec<Cell>> = BTreeMap::new();
    for (k, (target, counts)) in by_target.iter().enumerate() {
        let one = counts.get(&1);
        // Each target against its own one-island median, so that four targets of different
        // difficulty share one axis and "not worse than one island" is the line at 1.
        let scale = one
            .and_then(|one| Survival::new(one).median())
            .unwrap_or(f64::NAN);
        let colour = COLOURS[k % COLOURS.len()];
        // Targets side by side at each island count, so that their bars do not hide each other.
        let shift = 0.06 * (k as f64 - 1.5);
        let mut points = Vec::new();
        for (&islands, reaches) in counts.iter() {
            let survival = Survival::new(reaches);
            let median = survival.median();
            // log2 on a linear axis: a decade axis would run on to 100 islands.
            let x = f64::from(islands).log2() + shift;
            let (p, ratio) = match one {
                Some(one) if islands > 1 => {
                    by_islands
                        .entry(islands)
                        .or_default()
                        .push(Cell { runs: reaches, one });
                    let [lo, hi] = bootstrap_interval(
                        &[reaches, one],
                        RESAMPLES,
                        &mut cell_rng(target, islands),
                        |s| median_ratio(&s[0], &s[1]),
                    );
                    bars.push(Series {
                        label: String::new(),
                        colour,
                        points: vec![[x, lo.min(BAR_CEILING)], [x, hi.min(BAR_CEILING)]],
                        markers: false,
                    });
                    let finite = |v: f64| Some(v).filter(|v| v.is_finite());
                    (
                        format!("{:.2}", faster(&survival, &Survival::new(one))),
                        format!(
                            "{} ({}–{})",
                            show_ratio(median.map(|m| m / scale)),
                            show_ratio(finite(lo)),
                            show_ratio(finite(hi))
                        ),
                    )
                }
                _ => ("–".to_string(), "–".to_string()),
            };
            println!(
                "| {target} | {islands} | {} | {} | {} | {}–{} | {p} | {ratio} |",
                reaches.len(),
                reaches
                    .iter()
                    .filter(|r| matches!(r, Reach::Stopped(_)))
                    .count(),
                show(median),
                show(survival.quantile(0.25)),
                show(survival.quantile(0.75)),
            );
            points.push([x, median.unwrap_or(f64::NAN) / scale]);
        }
        series.push(Series {
            label: target.replace('_', " "),
            colour,
            points,
            markers: true,
        });
    }
    println!();
    println!(
        "| islands | targets | runs | P(faster than one island), mean over targets (90 % interval) |"
    );
    println!("|---|---|---|---|");
    for (&islands, cells) in &by_islands {
        println!("{}", pooled(cells, islands));
    }
    let most = runs
        .iter()
        .map(|r| f64::from(r.islands).log2())
        .fold(0.0, f64::max);
    series.push(Series {
        label: "one island".into(),
        colour: [150, 150, 150],
        points: vec![[0.0, 1.0], [most, 1.0]],
        markers: false,
    });
    series.extend(bars);
    if let Some(png) = args.get(1) {
        let spec = PlotSpec {
            title: format!("Islands at an equal total of 48 designs (bars cut at {BAR_CEILING})"),
            x_label: "islands, log2 (0: one island, 4: sixteen)".into(),
            // Drawn across the top and clipped beyond ~75 characters; the font has no apostrophe.
            y_label: "evaluations to paper value: median / one-island median (bars: 90 %)".into(),
            log_x: false,
            log_y: false,
        };
        let bytes = line_plot_over(&spec, &series, [None, Some((0.4, BAR_CEILING))])
            .to_png()
            .unwrap_or_else(|e| panic!("PNG encoding: {e}"));
        std::fs::write(png, bytes).unwrap_or_else(|e| {
            eprintln!("island_curve: {png}: {e}");
            std::process::exit(1);
        });
        eprintln!("island_curve: wrote {png}");
    }
}
