//! A search policy against the search it changes, seed by seed (issue 13). A run is a function of
//! its config and seed, and a policy such as `resolution.carry_checked_best` changes nothing before
//! it first acts, so one seed's two runs share everything up to there: their order compares the
//! policies without the seeds' spread, which an unpaired comparison has to outweigh with many more
//! runs.
//!
//! `cargo bench -p amorph-coordinator --bench paired_runs -- $PWD/docs/data/island_curve.csv
//! $PWD/docs/data/carry_checked.csv` (the baseline's runs, then the policy's: both in the format
//! of [`amorph_coordinator::study::parse_runs`]; a bench runs in its package's folder, hence the
//! absolute paths)
//!
//! Pairs the two files' rows by target, islands, population and seed, and prints one row per pair,
//! then one per target and setting: how many pairs the policy reached the target first, the
//! baseline first, both at the same count, and how many the data leave open (a run stopped before
//! the other's count); the two-sided sign test over the ordered pairs; and the paired seeds'
//! Kaplan–Meier medians under each, with their ratio. Rows of either file without a partner are
//! counted, not paired.

use std::cmp::Ordering;
use std::collections::BTreeMap;

use amorph_coordinator::study::{
    Reach, RecordedRun, Survival, paired_order, parse_runs, sign_test,
};

type Key = (String, u32, u32, u64);

/// One seed's runs: (seed, the baseline's, the policy's, the policy's order against the
/// baseline as far as the data fix it).
type Pair = (u64, Reach, Reach, Option<Ordering>);

/// A file's runs by (target, islands, population, seed); a key met twice is refused, since its
/// pair would be ambiguous.
fn keyed(path: &str) -> Result<BTreeMap<Key, Reach>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut runs = BTreeMap::new();
    for RecordedRun {
        target,
        islands,
        population,
        seed,
        reach,
    } in parse_runs(path, &text)?
    {
        let key = (target, islands, population, seed);
        if runs.insert(key.clone(), reach).is_some() {
            return Err(format!(
                "{path}: {} with {} × {} seed {} appears twice",
                key.0, key.1, key.2, key.3
            ));
        }
    }
    Ok(runs)
}

fn show(reach: Reach) -> String {
    match reach {
        Reach::Reached(n) => n.to_string(),
        Reach::Stopped(n) => format!(">{n}"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let [baseline, policy] = &args[..] else {
        eprintln!("paired_runs: usage: <baseline runs.csv> <policy runs.csv>");
        std::process::exit(2);
    };
    let (baseline, policy) = match (keyed(baseline), keyed(policy)) {
        (Ok(b), Ok(p)) => (b, p),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("paired_runs: {e}");
            std::process::exit(2);
        }
    };
    // Pairs by setting (target, islands, population), seeds in order.
    let mut settings: BTreeMap<(&str, u32, u32), Vec<Pair>> = BTreeMap::new();
    for ((target, islands, population, seed), &with) in &policy {
        if let Some(&without) = baseline.get(&(target.clone(), *islands, *population, *seed)) {
            (settings.entry((target, *islands, *population)).or_default()).push((
                *seed,
                without,
                with,
                paired_order(with, without),
            ));
        }
    }
    let paired: usize = settings.values().map(Vec::len).sum();
    println!("| target | islands × population | seed | baseline | policy | first |");
    println!("|---|---|---|---|---|---|");
    for ((target, islands, population), pairs) in &settings {
        for &(seed, without, with, order) in pairs {
            let first = match order {
                Some(Ordering::Less) => "policy",
                Some(Ordering::Greater) => "baseline",
                Some(Ordering::Equal) => "same",
                None => "open",
            };
            println!(
                "| {target} | {islands} × {population} | {seed} | {} | {} | {first} |",
                show(without),
                show(with)
            );
        }
    }
    println!();
    println!(
        "| target | islands × population | pairs | policy first | baseline first | same | open | sign test p | median, baseline | median, policy | ratio |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let median = |runs: &[Reach]| Survival::new(runs).median();
    let shown = |m: Option<f64>| m.map_or("beyond".to_string(), |m| format!("{m:.0}"));
    for ((target, islands, population), pairs) in &settings {
        let count = |o: Option<Ordering>| pairs.iter().filter(|p| p.3 == o).count() as u64;
        let (wins, losses) = (count(Some(Ordering::Less)), count(Some(Ordering::Greater)));
        let without: Vec<Reach> = pairs.iter().map(|p| p.1).collect();
        let with: Vec<Reach> = pairs.iter().map(|p| p.2).collect();
        let (m0, m1) = (median(&without), median(&with));
        let ratio = match (m0, m1) {
            (Some(a), Some(b)) => format!("{:.2}", b / a),
            _ => "–".to_string(),
        };
        println!(
            "| {target} | {islands} × {population} | {} | {wins} | {losses} | {} | {} | {:.3} | {} | {} | {ratio} |",
            pairs.len(),
            count(Some(Ordering::Equal)),
            count(None),
            sign_test(wins, losses),
            shown(m0),
            shown(m1),
        );
    }
    eprintln!(
        "paired_runs: {paired} pairs; {} policy runs and {} baseline runs without a partner",
        policy.len() - paired,
        baseline.len() - paired
    );
}
