//! What islands change when the finest level is one climb (issue 13, session 47).
//!
//! With `local_search.finest_fraction = 1` every child at the finest level is a nudge of the run's
//! best, whatever the island count, so a run's count to the paper's value is the evaluations its
//! coarse level took before the switch (E) plus the climb's from the design the switch handed over
//! (C), and islands can change only E and that design's error on the fine grid (R0). A hand-over
//! is cheap to measure (a run stopped right after the switch's re-evaluation: `deploy/study.sh run
//! ... --target 100`, half a minute), a whole run is not; so this bench measures the islands' effect on the
//! hand-over over many seeds, and the climb's cost against R0 over the whole runs already made.
//!
//! `cargo bench -p amorph-coordinator --bench handover -- $PWD/docs/data/handover.csv
//! $PWD/docs/data/finest_fraction.csv` (a bench runs in its package's folder, hence the paths)
//!
//! The first file has one row per hand-over, `target,islands,population,seed,switch_evaluations,
//! handover_rms_percent,session`; the second, optional, whole runs of the same search in the
//! format of [`amorph_coordinator::study::parse_runs`]. Prints, per target and island count, E's
//! and R0's medians and quartiles, P(R0 below a one-island hand-over's) (Mann–Whitney, ties half)
//! and R0's median against one island's with a 90 % bootstrap interval. With the runs: the fit
//! ln C = a + b ln R0 over the runs whose hand-over is in the first file (a run stopped short is
//! left out and counted: its C is only a lower bound), its mean residual per island count (the
//! climb being the same search for every count says these are noise around 0; again with the
//! stopped runs counted at their stop, a lower bound), and each count's
//! expected count E + C predicted from its hand-overs through the fit, against one island's.
//!
//! Key-off runs (`docs/data/island_curve.csv`) have the same hand-overs, the key acting only after
//! the switch, but a fine level that still breeds each island's crossover children: against them
//! the per-count residual is the measurement (what the fine level adds at that count, session 48),
//! and the expected count is what the hand-over alone is worth.

use std::collections::{BTreeMap, BTreeSet};

use amorph::task::beam::NamedProfile;

use amorph_coordinator::study::{Reach, RecordedRun, Survival, bootstrap_interval, parse_runs};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const HEADER: &str =
    "target,islands,population,seed,switch_evaluations,handover_rms_percent,session";

/// Redraws per interval (as in `island_curve`: read an end to a tenth).
const RESAMPLES: usize = 10_000;

/// The fewest finished climbs a target's fit is drawn through.
const MIN_CLIMBS: usize = 10;

type Key = (String, u32, u32, u64);

/// One hand-over: evaluations at the switch, its re-evaluations included, and the best design's
/// RMS error (%) on the final grid there, before any child of the finest level.
#[derive(Clone, Copy, Debug)]
struct Handover {
    switch: f64,
    rms: f64,
}

/// A run whose hand-over is known: ln R0, and ln C for a run that reached the paper's value.
#[derive(Clone, Copy, Debug)]
struct Climb {
    islands: u32,
    ln_rms: f64,
    ln_climb: f64,
}

fn parse_handovers(path: &str) -> Result<BTreeMap<Key, Handover>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut lines = text.lines().enumerate();
    if lines.next().map(|(_, l)| l.trim()) != Some(HEADER) {
        return Err(format!("{path}:1: expected the header {HEADER}"));
    }
    let mut rows = BTreeMap::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let at = |what: &str| format!("{path}:{}: {what}", i + 1);
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [target, islands, population, seed, switch, rms, _session] = fields[..] else {
            return Err(at("expected seven comma-separated fields"));
        };
        let count = |text: &str, field: &str| {
            (text.parse().ok())
                .filter(|&n: &u32| n > 0)
                .ok_or_else(|| at(&format!("{field}: a positive count")))
        };
        let positive = |text: &str, field: &str| {
            (text.parse().ok())
                .filter(|&v: &f64| v.is_finite() && v > 0.0)
                .ok_or_else(|| at(&format!("{field}: a positive number")))
        };
        let key = (
            target.to_string(),
            count(islands, "islands")?,
            count(population, "population")?,
            seed.parse().map_err(|_| at("seed: a whole number"))?,
        );
        let handover = Handover {
            switch: positive(switch, "switch_evaluations")?,
            rms: positive(rms, "handover_rms_percent")?,
        };
        if rows.insert(key, handover).is_some() {
            return Err(at(
                "a second row for this target, islands, population and seed",
            ));
        }
    }
    Ok(rows)
}

fn quantile(values: &[f64], q: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let at = q * (v.len() - 1) as f64;
    let (lo, hi) = (at.floor() as usize, at.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (at - lo as f64)
}

/// P(a draw from `a` is below one from `b`), ties half.
fn below(a: &[f64], b: &[f64]) -> f64 {
    let score: f64 = a
        .iter()
        .flat_map(|x| b.iter().map(move |y| (x, y)))
        .map(|(x, y)| match x.total_cmp(y) {
            std::cmp::Ordering::Less => 1.0,
            std::cmp::Ordering::Equal => 0.5,
            std::cmp::Ordering::Greater => 0.0,
        })
        .sum();
    score / (a.len() * b.len()) as f64
}

/// A fit ln C = a + b ln R0: (a, b, r, the smearing factor mean(exp(residual))).
type Fit = (f64, f64, f64, f64);

/// How much longer a climb was than the fit expects, in ln C.
fn residual((a, b, _, _): Fit, c: &Climb) -> f64 {
    c.ln_climb - a - b * c.ln_rms
}

/// Least squares.
fn fit(climbs: &[Climb]) -> Fit {
    let n = climbs.len() as f64;
    let mx = climbs.iter().map(|c| c.ln_rms).sum::<f64>() / n;
    let my = climbs.iter().map(|c| c.ln_climb).sum::<f64>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for c in climbs {
        let (dx, dy) = (c.ln_rms - mx, c.ln_climb - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let b = sxy / sxx;
    let a = my - b * mx;
    let smear = climbs
        .iter()
        .map(|c| residual((a, b, 0.0, 0.0), c).exp())
        .sum::<f64>()
        / n;
    (a, b, sxy / (sxx * syy).sqrt(), smear)
}

fn rng(stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(47);
    rng.set_stream(stream);
    rng
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let Some(path) = args.first() else {
        eprintln!("handover: usage: <handover.csv> [<runs.csv>]");
        std::process::exit(2);
    };
    let fail = |e: String| -> ! {
        eprintln!("handover: {e}");
        std::process::exit(2);
    };
    let handovers = parse_handovers(path).unwrap_or_else(|e| fail(e));
    let mut cells: BTreeMap<(&str, u32), Vec<Handover>> = BTreeMap::new();
    for ((target, islands, _, _), h) in &handovers {
        cells.entry((target, *islands)).or_default().push(*h);
    }
    println!(
        "| target | islands | hand-overs | E: median (quartiles) | R0 %: median (quartiles) | P(R0 below one island's) | R0 median ÷ one island's (90 %) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (&(target, islands), list) in &cells {
        let switch: Vec<f64> = list.iter().map(|h| h.switch).collect();
        let rms: Vec<f64> = list.iter().map(|h| h.rms).collect();
        let one: Option<Vec<f64>> = cells
            .get(&(target, 1))
            .filter(|_| islands > 1)
            .map(|o| o.iter().map(|h| h.rms).collect());
        let (p, ratio) = match &one {
            Some(one) => {
                let median = |s: &[f64]| quantile(s, 0.5);
                let [lo, hi] = bootstrap_interval(
                    &[&rms[..], &one[..]],
                    RESAMPLES,
                    &mut rng(u64::from(islands)),
                    |s| median(&s[0]) / median(&s[1]),
                );
                (
                    format!("{:.2}", below(&rms, one)),
                    format!("{:.2} ({lo:.2}–{hi:.2})", median(&rms) / median(one)),
                )
            }
            None => ("–".into(), "–".into()),
        };
        println!(
            "| {target} | {islands} | {} | {:.0} ({:.0}–{:.0}) | {:.3} ({:.3}–{:.3}) | {p} | {ratio} |",
            list.len(),
            quantile(&switch, 0.5),
            quantile(&switch, 0.25),
            quantile(&switch, 0.75),
            quantile(&rms, 0.5),
            quantile(&rms, 0.25),
            quantile(&rms, 0.75),
        );
    }
    let Some(runs_path) = args.get(1) else {
        return;
    };
    let runs = std::fs::read_to_string(runs_path)
        .map_err(|e| format!("{runs_path}: {e}"))
        .and_then(|text| parse_runs(runs_path, &text))
        .unwrap_or_else(|e| fail(e));
    climb_against_handover(&handovers, &runs, &cells);
}

/// The paper's simulated error for a target (Table III): a hand-over at or below it needs no
/// climb.
fn paper_value(target: &str) -> Option<f64> {
    NamedProfile::from_name(target).and_then(NamedProfile::paper_rms_percent)
}

/// Mean over hand-overs of E + C, C predicted from R0 through the fit (Duan's smearing keeps it the
/// mean of C, not of ln C), and none for a hand-over already at the paper's value.
fn expected_count(handovers: &[Handover], paper: f64, (a, b, _, smear): Fit) -> f64 {
    handovers
        .iter()
        .map(|h| {
            let climb = if h.rms <= paper {
                0.0
            } else {
                (a + b * h.rms.ln()).exp() * smear
            };
            h.switch + climb
        })
        .sum::<f64>()
        / handovers.len() as f64
}

/// The second half: per target, the climb's cost against the hand-over, and each island count's
/// expected count through it.
fn climb_against_handover(
    handovers: &BTreeMap<Key, Handover>,
    runs: &[RecordedRun],
    cells: &BTreeMap<(&str, u32), Vec<Handover>>,
) {
    let targets: BTreeSet<&str> = cells.keys().map(|(t, _)| *t).collect();
    for target in targets {
        let Some(paper) = paper_value(target) else {
            println!("\n{target}: no paper value, no climb to fit");
            continue;
        };
        let (mut climbs, mut stopped, mut at_switch, mut early) = (Vec::new(), Vec::new(), 0, 0);
        let mut measured: BTreeMap<u32, Vec<Reach>> = BTreeMap::new();
        for run in runs.iter().filter(|r| r.target == target) {
            let key = (run.target.clone(), run.islands, run.population, run.seed);
            let Some(h) = handovers.get(&key) else {
                continue;
            };
            measured.entry(run.islands).or_default().push(run.reach);
            let climb = |n: u64| Climb {
                islands: run.islands,
                ln_rms: h.rms.ln(),
                ln_climb: (n as f64 - h.switch).ln(),
            };
            match run.reach {
                Reach::Reached(n) if h.rms > paper && n as f64 > h.switch => climbs.push(climb(n)),
                Reach::Reached(_) => at_switch += 1,
                // Its climb is at least this long; kept apart for the residuals' lower bound.
                Reach::Stopped(n) if n as f64 > h.switch => stopped.push(climb(n)),
                // Stopped before its switch: it says nothing of the climb.
                Reach::Stopped(_) => early += 1,
            }
        }
        // Two parameters through a handful of climbs whose luck spreads ln C by 0.6-1.1 (the arc,
        // the polynomial) fit that luck, not the hand-over's effect: session 41's seven polynomial
        // climbs with the key predicted one island a mean count of 43,000.
        if climbs.len() < MIN_CLIMBS {
            println!(
                "\n{target}: {} climbs with a known hand-over, fewer than {MIN_CLIMBS}, no fit",
                climbs.len()
            );
            continue;
        }
        let line = fit(&climbs);
        let [lo, hi] =
            bootstrap_interval(&[&climbs[..]], RESAMPLES, &mut rng(1000), |s| fit(&s[0]).1);
        let spread = (climbs
            .iter()
            .map(|c| residual(line, c).powi(2))
            .sum::<f64>()
            / (climbs.len() - 2) as f64)
            .sqrt();
        println!(
            "\n{target}: climb C = count − E against R0 over {} runs ({at_switch} done at the switch, \
             {} stopped short, {early} stopped before the switch, all left out): ln C = {:.2} + {:.2} ln R0 (90 % interval of \
             the slope {lo:.2}–{hi:.2}), r = {:.2}, residual spread {spread:.2}",
            climbs.len(),
            stopped.len(),
            line.0,
            line.1,
            line.2
        );
        println!(
            "\n| islands | climbs fitted | mean residual of ln C | with the stopped runs at their stop (a lower bound) | expected count from the hand-overs | ÷ one island's (90 %) | measured median of the runs |"
        );
        println!("|---|---|---|---|---|---|---|");
        let one = cells.get(&(target, 1));
        for (&(_, islands), list) in cells.range((target, 0)..=(target, u32::MAX)) {
            let residuals = |of: &[Climb]| -> Vec<f64> {
                of.iter()
                    .filter(|c| c.islands == islands)
                    .map(|c| residual(line, c))
                    .collect()
            };
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let own = residuals(&climbs);
            let residual = if own.is_empty() {
                "–".to_string()
            } else {
                format!("{:+.2}", mean(&own))
            };
            let cut = residuals(&stopped);
            let bound = if cut.is_empty() {
                "–".to_string()
            } else {
                format!("≥ {:+.2}", mean(&[own.clone(), cut].concat()))
            };
            let expected = expected_count(list, paper, line);
            let ratio = match one.filter(|_| islands > 1) {
                Some(one) => {
                    // The fit is redrawn with the hand-overs: how much a lower R0 is worth is as
                    // uncertain as the slope.
                    let mut fit_rng = rng(3000 + u64::from(islands));
                    let mut redrawn = Vec::with_capacity(climbs.len());
                    let [lo, hi] = bootstrap_interval(
                        &[&list[..], &one[..]],
                        RESAMPLES,
                        &mut rng(2000 + u64::from(islands)),
                        |s| {
                            redrawn.clear();
                            redrawn.extend(
                                (0..climbs.len())
                                    .map(|_| climbs[fit_rng.random_range(0..climbs.len())]),
                            );
                            let line = fit(&redrawn);
                            expected_count(&s[0], paper, line) / expected_count(&s[1], paper, line)
                        },
                    );
                    format!(
                        "{:.2} ({lo:.2}–{hi:.2})",
                        expected / expected_count(one, paper, line)
                    )
                }
                None => "–".into(),
            };
            let median = measured
                .get(&islands)
                .and_then(|m| Survival::new(m).median())
                .map_or("–".to_string(), |m| format!("{m:.0}"));
            println!(
                "| {islands} | {} | {residual} | {bound} | {expected:.0} | {ratio} | {median} |",
                own.len()
            );
        }
    }
}
