//! Statistics over a study's runs: how many evaluations each run took to reach a target error,
//! where some runs were stopped short of it (a lease ended, a session ended, the budget ran out).
//!
//! A stopped run is *censored*: it says "not reached in the first N evaluations", not "never".
//! Counting it as later than every finished run (what `island_curve` did until session 33) is
//! right only when N exceeds every finished count; a run a lease cut at 5,000 evaluations says
//! nothing about whether it would have beaten a finished run's 7,000. So the median and quantiles
//! here are read off the Kaplan–Meier estimate of the probability a run has not yet reached the
//! target, and P(faster) is Efron's: the chance a run of one sample reaches it before a run of
//! the other, integrated over both estimates, where the order of two runs is counted only as far
//! as the data fix it. With no stopped run, both reduce to the plain median (the midpoint of the
//! middle two for an even count) and the Mann–Whitney fraction with ties half, which the tests
//! check.

use std::cmp::Ordering;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// One run's outcome against its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// First reached the target at this many evaluations.
    Reached(u64),
    /// Stopped after this many evaluations without reaching it.
    Stopped(u64),
}

impl Reach {
    /// `"N"` for a run that reached the target at N, `">N"` for one stopped short after N.
    pub fn parse(text: &str) -> Option<Self> {
        match text.trim().strip_prefix('>') {
            Some(n) => n.parse().ok().map(Reach::Stopped),
            None => text.trim().parse().ok().map(Reach::Reached),
        }
    }

    fn count(self) -> u64 {
        match self {
            Reach::Reached(n) | Reach::Stopped(n) => n,
        }
    }
}

/// One row of a study's CSV (`docs/data/island_curve.csv` and the policy studies beside it):
/// `target,islands,population,seed,evaluations,session`, where `evaluations` is the count at which
/// the run first reached the target, or `>N` for a run stopped short after N.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedRun {
    pub target: String,
    pub islands: u32,
    pub population: u32,
    pub seed: u64,
    pub reach: Reach,
}

pub const RUNS_HEADER: &str = "target,islands,population,seed,evaluations,session";

/// The runs of a study's CSV; a malformed line is refused with its file, line and field.
pub fn parse_runs(path: &str, text: &str) -> Result<Vec<RecordedRun>, String> {
    let mut lines = text.lines().enumerate();
    if lines.next().map(|(_, l)| l.trim()) != Some(RUNS_HEADER) {
        return Err(format!("{path}:1: expected the header {RUNS_HEADER}"));
    }
    let mut runs = Vec::new();
    for (i, line) in lines {
        let at = |what: &str| format!("{path}:{}: {what}", i + 1);
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let [target, islands, population, seed, evaluations, _session] = fields[..] else {
            return Err(at("expected six comma-separated fields"));
        };
        let positive = |text: &str, field: &str| {
            (text.parse().ok())
                .filter(|&n: &u32| n > 0)
                .ok_or_else(|| at(&format!("{field}: a positive count")))
        };
        runs.push(RecordedRun {
            target: target.to_string(),
            islands: positive(islands, "islands")?,
            population: positive(population, "population")?,
            seed: seed.parse().map_err(|_| at("seed: a whole number"))?,
            reach: Reach::parse(evaluations)
                .ok_or_else(|| at("evaluations: a count, or >N for a run stopped short after N"))?,
        });
    }
    Ok(runs)
}

/// Two probabilities closer than this are equal: the estimate is a product of ratios of small
/// counts, so an exact 0.5 arrives as 0.5 ± a few ulps.
const SAME: f64 = 1e-12;

/// The Kaplan–Meier estimate of P(a run has not reached the target after t evaluations), kept as
/// the probability mass it puts at each finished count, plus the mass left beyond the last one.
#[derive(Clone, Debug)]
pub struct Survival {
    /// (evaluations, probability of first reaching the target there), counts increasing.
    steps: Vec<(u64, f64)>,
    /// Mass of runs not known to reach the target at all: the runs stopped after the last
    /// finished one, wherever they would have finished.
    tail: f64,
    /// The tail lies beyond this count (the earliest stop among those runs).
    tail_after: u64,
}

impl Survival {
    /// The estimate from a sample of runs; an empty sample puts all its mass in the tail.
    pub fn new(runs: &[Reach]) -> Self {
        let mut sorted = runs.to_vec();
        // At equal counts a finished run comes first: a run stopped at N was still short at N, so
        // it was at risk when the other reached the target.
        sorted.sort_by_key(|r| (r.count(), matches!(r, Reach::Stopped(_))));
        let mut steps = Vec::new();
        let mut left = 1.0;
        let mut at_risk = sorted.len();
        for same in sorted.chunk_by(|a, b| a.count() == b.count()) {
            let reached = same
                .iter()
                .filter(|r| matches!(r, Reach::Reached(_)))
                .count();
            if reached > 0 {
                let after = left * (1.0 - reached as f64 / at_risk as f64);
                steps.push((same[0].count(), left - after));
                left = after;
            }
            at_risk -= same.len();
        }
        let last = steps.last().map_or(0, |&(count, _)| count);
        let tail_after = sorted
            .iter()
            .filter_map(|r| match *r {
                Reach::Stopped(n) if n >= last => Some(n),
                _ => None,
            })
            .min()
            .unwrap_or(last);
        Survival {
            steps,
            tail: left.max(0.0),
            tail_after,
        }
    }

    /// The evaluations by which a fraction `q` of runs reach the target: the first count where
    /// the estimate of runs still short falls to 1 − q or below. Where it sits exactly at 1 − q
    /// between two counts, the midpoint (so that the median of an even sample is the midpoint of
    /// its middle two); `None` where fewer than `q` are known to reach it.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        let mut left = 1.0;
        for (k, &(count, mass)) in self.steps.iter().enumerate() {
            left -= mass;
            if left < 1.0 - q - SAME {
                return Some(count as f64);
            }
            if left <= 1.0 - q + SAME {
                // Flat at exactly 1 − q up to the next finished count; with none, the quantile
                // lies somewhere beyond, among the stopped runs.
                return self
                    .steps
                    .get(k + 1)
                    .map(|&(next, _)| 0.5 * (count + next) as f64);
            }
        }
        None
    }

    pub fn median(&self) -> Option<f64> {
        self.quantile(0.5)
    }
}

/// P(a run of `a` reaches the target before a run of `b`), ties counting half. Where the data
/// leave the order open (a run of one sample stopped before a finished count of the other, or two
/// runs that both never finished), the pair counts half, as a tie would.
pub fn faster(a: &Survival, b: &Survival) -> f64 {
    let order = |x: u64, y: u64| match x.cmp(&y) {
        std::cmp::Ordering::Less => 1.0,
        std::cmp::Ordering::Equal => 0.5,
        std::cmp::Ordering::Greater => 0.0,
    };
    let mut p = 0.0;
    for &(x, mass_a) in &a.steps {
        for &(y, mass_b) in &b.steps {
            p += mass_a * mass_b * order(x, y);
        }
        // `b`'s tail reaches the target (if ever) only after `tail_after`.
        p += mass_a * b.tail * if x <= b.tail_after { 1.0 } else { 0.5 };
    }
    for &(y, mass_b) in &b.steps {
        p += a.tail * mass_b * if y <= a.tail_after { 0.0 } else { 0.5 };
    }
    p + 0.5 * a.tail * b.tail
}

/// The order of one seed's two runs under two policies, as far as the data fix it: `Less` where
/// `a` reached the target first, `Equal` where both reached it at the same count, `None` where a
/// run stopped before the other's count (or both stopped) leaves it open. A seed fixes everything
/// up to where the policies differ, so such pairs compare the policies alone, without the seeds'
/// spread between them.
pub fn paired_order(a: Reach, b: Reach) -> Option<Ordering> {
    match (a, b) {
        (Reach::Reached(x), Reach::Reached(y)) => Some(x.cmp(&y)),
        // Stopped at y without reaching it: any count up to y came first.
        (Reach::Reached(x), Reach::Stopped(y)) => (x <= y).then_some(Ordering::Less),
        (Reach::Stopped(x), Reach::Reached(y)) => (y <= x).then_some(Ordering::Greater),
        (Reach::Stopped(_), Reach::Stopped(_)) => None,
    }
}

/// The two-sided exact sign test: the probability, were either policy as likely to win each
/// pair, of a split at least as uneven as `wins` against `losses` (ties and open pairs left out).
pub fn sign_test(wins: u64, losses: u64) -> f64 {
    let n = wins + losses;
    let fewer = wins.min(losses);
    // C(n, k) / 2^n summed for k ≤ fewer, term by term so that no factorial overflows.
    let mut term = 0.5_f64.powi(n as i32);
    let mut tail = term;
    for k in 1..=fewer {
        term *= (n - k + 1) as f64 / k as f64;
        tail += term;
    }
    (2.0 * tail).min(1.0)
}

/// The 5th and 95th percentiles of `statistic` over `resamples` redraws of the samples, each
/// redrawn with replacement to its own size (a percentile bootstrap). NaN statistics sort last.
/// A sample's items are runs' outcomes, or whole records (a run's hand-over and its count) where
/// a statistic needs several figures of one run to stay together.
pub fn bootstrap_interval<T: Copy>(
    samples: &[&[T]],
    resamples: usize,
    rng: &mut ChaCha8Rng,
    mut statistic: impl FnMut(&[Vec<T>]) -> f64,
) -> [f64; 2] {
    let mut drawn: Vec<Vec<T>> = samples
        .iter()
        .map(|s| Vec::with_capacity(s.len()))
        .collect();
    let mut values: Vec<f64> = (0..resamples)
        .map(|_| {
            for (sample, redraw) in samples.iter().zip(&mut drawn) {
                redraw.clear();
                redraw.extend((0..sample.len()).map(|_| sample[rng.random_range(0..sample.len())]));
            }
            statistic(&drawn)
        })
        .collect();
    values.sort_by(f64::total_cmp);
    let at = |f: f64| values[(f * (resamples - 1) as f64).round() as usize];
    [at(0.05), at(0.95)]
}

#[cfg(test)]
mod tests;
