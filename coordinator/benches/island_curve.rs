//! The island curve of issue 13 from its recorded runs: evaluations to the paper's Table III value
//! against the number of islands, per target, at an equal total (islands × population = 48 and a
//! batch of 48; docs/evolution.md, sessions 21–27).
//!
//! `cargo bench -p amorph-coordinator --bench island_curve -- $PWD/docs/data/island_curve.csv
//! $PWD/docs/img/island_curve.png` (a bench runs in its package's folder, hence the absolute paths)
//!
//! The CSV holds one row per run, `target,islands,population,seed,evaluations,session`, where
//! `evaluations` is the count at which the run first reached the paper's value, or `>N` for a run
//! stopped short after N. Prints one Markdown row per target and island count (runs, median,
//! quartiles, P: the probability that a run of that count reaches the paper's value before a
//! one-island run, ties counting half, and the median's ratio to one island's with its 90 %
//! bootstrap interval) and draws the ratios, one line per target, with their intervals as bars.
//!
//! A stopped run counts as later than any finished one, so a median or quartile that falls on one
//! is "beyond" the budget, whatever the budget was. One island is every one-island run of the
//! target, population 48 and 50 together: the same search from two more or fewer random designs
//! (session 26 found the two samples' medians 1.8–2.3 times apart, both ways, so neither alone is
//! the baseline).
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
use rand::{RngExt, SeedableRng};
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

/// Evaluations to the paper's value; `None` for a run stopped short of it.
type Reach = Option<u64>;

struct Run {
    target: String,
    islands: u32,
    reach: Reach,
}

fn parse(path: &str, text: &str) -> Result<Vec<Run>, String> {
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, l)| l.trim());
    if header != Some("target,islands,population,seed,evaluations,session") {
        return Err(format!(
            "{path}:1: expected the header target,islands,population,seed,evaluations,session"
        ));
    }
    let mut runs = Vec::new();
    for (i, line) in lines {
        let at = |what: &str| format!("{path}:{}: {what}", i + 1);
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [target, islands, _population, _seed, evaluations, _session] = fields[..] else {
            return Err(at("expected six comma-separated fields"));
        };
        let islands = islands
            .parse()
            .ok()
            .filter(|&n: &u32| n > 0)
            .ok_or_else(|| at("islands: a positive count"))?;
        let reach = match evaluations.strip_prefix('>') {
            Some(stopped) => stopped
                .parse::<u64>()
                .map(|_| None)
                .map_err(|_| at("evaluations: >N for a stopped run"))?,
            None => Some(
                evaluations
                    .parse()
                    .map_err(|_| at("evaluations: a count, or >N for a stopped run"))?,
            ),
        };
        runs.push(Run {
            target: target.to_string(),
            islands,
            reach,
        });
    }
    Ok(runs)
}

/// Sort key that puts a stopped run after every finished one.
fn late(r: &Reach) -> u64 {
    r.unwrap_or(u64::MAX)
}

/// The median (the midpoint of the middle two for an even count) and the quartiles as
/// `deploy/study.sh summary` takes them (the run at rank f·(n − 1), ties to even); `None` where
/// that falls on a stopped run.
fn median(sorted: &[Reach]) -> Option<f64> {
    let n = sorted.len();
    let (lo, hi) = (sorted[(n - 1) / 2]?, sorted[n / 2]?);
    Some(0.5 * (lo + hi) as f64)
}

fn quartile(sorted: &[Reach], f: f64) -> Option<f64> {
    let rank = (f * (sorted.len() - 1) as f64).round_ties_even() as usize;
    sorted[rank].map(|v| v as f64)
}

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

/// The 90 % percentile-bootstrap interval of median(a) / median(b), a stopped run counting as
/// infinitely late (so an interval can end at infinity).
fn ratio_interval(a: &[Reach], b: &[Reach], rng: &mut ChaCha8Rng) -> [f64; 2] {
    let mut redraw = |sample: &[Reach], scratch: &mut Vec<Reach>| {
        scratch.clear();
        scratch.extend((0..sample.len()).map(|_| sample[rng.random_range(0..sample.len())]));
        scratch.sort_by_key(late);
        median(scratch).unwrap_or(f64::INFINITY)
    };
    let (mut sa, mut sb) = (Vec::new(), Vec::new());
    let mut ratios: Vec<f64> = (0..RESAMPLES)
        .map(|_| redraw(a, &mut sa) / redraw(b, &mut sb))
        .collect();
    ratios.sort_by(f64::total_cmp);
    let at = |f: f64| ratios[(f * (RESAMPLES - 1) as f64).round() as usize];
    [at(0.05), at(0.95)]
}

/// P(a run of `a` reaches the value before a run of `b`), ties half; two stopped runs tie.
fn faster(a: &[Reach], b: &[Reach]) -> f64 {
    let wins: f64 = a
        .iter()
        .flat_map(|x| b.iter().map(move |y| (late(x), late(y))))
        .map(|(x, y)| match x.cmp(&y) {
            std::cmp::Ordering::Less => 1.0,
            std::cmp::Ordering::Equal => 0.5,
            std::cmp::Ordering::Greater => 0.0,
        })
        .sum();
    wins / (a.len() * b.len()) as f64
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
        .and_then(|text| parse(csv, &text))
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
        "| target | islands | runs | median | quartiles | P(faster than one island) | median ÷ one island's (90 % interval) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let (mut series, mut bars) = (Vec::new(), Vec::new());
    for (k, (target, counts)) in by_target.iter_mut().enumerate() {
        for reaches in counts.values_mut() {
            reaches.sort_by_key(late);
        }
        let one = counts.get(&1);
        // Each target against its own one-island median, so that four targets of different
        // difficulty share one axis and "not worse than one island" is the line at 1.
        let scale = one.and_then(|one| median(one)).unwrap_or(f64::NAN);
        let colour = COLOURS[k % COLOURS.len()];
        // Targets side by side at each island count, so that their bars do not hide each other.
        let shift = 0.06 * (k as f64 - 1.5);
        let mut points = Vec::new();
        for (&islands, reaches) in counts.iter() {
            let median = median(reaches);
            // log2 on a linear axis: a decade axis would run on to 100 islands.
            let x = f64::from(islands).log2() + shift;
            let (p, ratio) = match one {
                Some(one) if islands > 1 => {
                    let [lo, hi] = ratio_interval(reaches, one, &mut cell_rng(target, islands));
                    bars.push(Series {
                        label: String::new(),
                        colour,
                        points: vec![[x, lo.min(BAR_CEILING)], [x, hi.min(BAR_CEILING)]],
                        markers: false,
                    });
                    let finite = |v: f64| Some(v).filter(|v| v.is_finite());
                    (
                        format!("{:.2}", faster(reaches, one)),
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
                "| {target} | {islands} | {} | {} | {}–{} | {p} | {ratio} |",
                reaches.len(),
                show(median),
                show(quartile(reaches, 0.25)),
                show(quartile(reaches, 0.75)),
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
