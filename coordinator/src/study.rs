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
pub fn bootstrap_interval(
    samples: &[&[Reach]],
    resamples: usize,
    rng: &mut ChaCha8Rng,
    mut statistic: impl FnMut(&[Vec<Reach>]) -> f64,
) -> [f64; 2] {
    let mut drawn: Vec<Vec<Reach>> = samples
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
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn reached(counts: &[u64]) -> Vec<Reach> {
        counts.iter().map(|&n| Reach::Reached(n)).collect()
    }

    #[test]
    fn without_stopped_runs_the_median_is_the_plain_median() {
        let odd = Survival::new(&reached(&[700, 300, 500, 900, 100]));
        assert_eq!(odd.median(), Some(500.0));
        let even = Survival::new(&reached(&[400, 100, 300, 200]));
        assert_eq!(even.median(), Some(250.0));
        assert_eq!(even.quantile(0.25), Some(150.0));
        assert_eq!(even.quantile(0.75), Some(350.0));
        assert_eq!(
            Survival::new(&reached(&[100, 100, 200])).median(),
            Some(100.0)
        );
        assert_eq!(Survival::new(&reached(&[100, 100])).median(), Some(100.0));
    }

    /// Kaplan and Meier's own arithmetic on a sample worked by hand: 1, 2+, 3, 3, 4+, 5 (+ for
    /// stopped). At 1: 6 at risk, S = 5/6; at 3: 4 at risk, two reach, S = 5/6 · 2/4 = 5/12; at
    /// 5: 1 at risk, S = 0.
    #[test]
    fn a_censored_sample_follows_the_product_limit() {
        let runs = [
            Reach::Reached(1),
            Reach::Stopped(2),
            Reach::Reached(3),
            Reach::Reached(3),
            Reach::Stopped(4),
            Reach::Reached(5),
        ];
        let s = Survival::new(&runs);
        let masses: Vec<(u64, f64)> = s.steps.clone();
        let expected = [(1, 1.0 / 6.0), (3, 5.0 / 12.0), (5, 5.0 / 12.0)];
        assert_eq!(masses.len(), expected.len());
        for ((c, m), (ce, me)) in masses.iter().zip(expected) {
            assert_eq!(*c, ce);
            assert!((m - me).abs() < 1e-15, "{c}: {m} against {me}");
        }
        assert_eq!(s.tail, 0.0);
        // Counted later than every finished run, the two stopped runs would make it 4.
        assert_eq!(s.median(), Some(3.0));
        assert_eq!(s.quantile(0.9), Some(5.0));
    }

    #[test]
    fn runs_stopped_after_every_finished_one_leave_the_old_convention_unchanged() {
        let mut runs = reached(&[100, 200, 300]);
        runs.extend([Reach::Stopped(1000), Reach::Stopped(2000)]);
        let s = Survival::new(&runs);
        assert_eq!(s.median(), Some(300.0));
        assert_eq!(s.quantile(0.7), None);
        assert!((s.tail - 0.4).abs() < 1e-15);
    }

    #[test]
    fn a_run_stopped_early_does_not_count_as_the_latest() {
        // Counted last, the stopped run would make the median 400; as censored at 50 it tells
        // nothing about the other three, whose median is 300.
        let runs = [
            Reach::Stopped(50),
            Reach::Reached(200),
            Reach::Reached(300),
            Reach::Reached(400),
        ];
        assert_eq!(Survival::new(&runs).median(), Some(300.0));
    }

    #[test]
    fn p_faster_is_the_mann_whitney_fraction_without_stopped_runs() {
        let a = reached(&[1, 4, 4, 9]);
        let b = reached(&[2, 4, 7]);
        // Pairs (a before b): 1 beats 3; each 4 beats 7, ties 4, loses to 2: 1.5 each; 9: 0.
        let expected = (3.0 + 1.5 + 1.5 + 0.0) / 12.0;
        let p = faster(&Survival::new(&a), &Survival::new(&b));
        assert!((p - expected).abs() < 1e-15, "{p}");
    }

    #[test]
    fn p_faster_of_two_samples_both_ways_adds_to_one() {
        let a = [
            Reach::Reached(300),
            Reach::Stopped(250),
            Reach::Reached(900),
            Reach::Stopped(5000),
        ];
        let b = [
            Reach::Reached(100),
            Reach::Reached(400),
            Reach::Stopped(600),
            Reach::Reached(700),
        ];
        let (sa, sb) = (Survival::new(&a), Survival::new(&b));
        let sum = faster(&sa, &sb) + faster(&sb, &sa);
        assert!((sum - 1.0).abs() < 1e-12, "{sum}");
        assert!((faster(&sa, &sa) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn an_unfinished_tail_is_ordered_only_where_the_data_fix_it() {
        // `a` reached at 100 and 500; `b`'s one run was stopped at 300. 100 is known to come
        // first; 500 against a run still short at 300 is open, so it counts half.
        let a = Survival::new(&reached(&[100, 500]));
        let b = Survival::new(&[Reach::Stopped(300)]);
        assert!((faster(&a, &b) - 0.75).abs() < 1e-15);
    }

    #[test]
    fn the_bootstrap_of_a_constant_sample_is_that_constant() {
        let runs = reached(&[400, 400, 400]);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let [lo, hi] = bootstrap_interval(&[&runs], 200, &mut rng, |s| {
            Survival::new(&s[0]).median().unwrap_or(f64::INFINITY)
        });
        assert_eq!([lo, hi], [400.0, 400.0]);
    }

    #[test]
    fn a_pair_is_ordered_only_where_the_data_fix_it() {
        use Reach::{Reached, Stopped};
        assert_eq!(
            paired_order(Reached(300), Reached(500)),
            Some(Ordering::Less)
        );
        assert_eq!(
            paired_order(Reached(500), Reached(500)),
            Some(Ordering::Equal)
        );
        // Stopped at 500 without the target: a run that reached it at 500 or sooner came first.
        assert_eq!(
            paired_order(Reached(500), Stopped(500)),
            Some(Ordering::Less)
        );
        assert_eq!(paired_order(Reached(501), Stopped(500)), None);
        assert_eq!(
            paired_order(Stopped(900), Reached(200)),
            Some(Ordering::Greater)
        );
        assert_eq!(paired_order(Stopped(900), Stopped(20_000)), None);
    }

    #[test]
    fn the_sign_test_is_the_binomial_tail_doubled() {
        // 9 wins in 10: 2 (C(10,0) + C(10,1)) / 2^10 = 22 / 1024.
        assert!((sign_test(9, 1) - 22.0 / 1024.0).abs() < 1e-15);
        assert_eq!(sign_test(1, 9), sign_test(9, 1));
        // An even split, or no pair at all, is no evidence either way.
        assert_eq!(sign_test(5, 5), 1.0);
        assert_eq!(sign_test(0, 0), 1.0);
        // 6 of 6 one way: 2 / 64.
        assert!((sign_test(6, 0) - 2.0 / 64.0).abs() < 1e-15);
    }

    #[test]
    fn a_study_csv_parses_and_a_bad_line_names_its_place() {
        let text =
            format!("{RUNS_HEADER}\ncircular_arc,8,6,3,>5011,34\n\nstraight,1,50,2,2142,20\n");
        let runs = parse_runs("runs.csv", &text).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(
            runs[0],
            RecordedRun {
                target: "circular_arc".into(),
                islands: 8,
                population: 6,
                seed: 3,
                reach: Reach::Stopped(5011),
            }
        );
        let bad = format!("{RUNS_HEADER}\nstraight,1,50,2,2142,20\nstraight,0,50,2,2142,20\n");
        assert_eq!(
            parse_runs("runs.csv", &bad).unwrap_err(),
            "runs.csv:3: islands: a positive count"
        );
        assert_eq!(
            parse_runs("runs.csv", "target,seed\n").unwrap_err(),
            format!("runs.csv:1: expected the header {RUNS_HEADER}")
        );
        let short = format!("{RUNS_HEADER}\nstraight,1,50,2,2142\n");
        assert_eq!(
            parse_runs("runs.csv", &short).unwrap_err(),
            "runs.csv:2: expected six comma-separated fields"
        );
    }

    #[test]
    fn counts_parse_with_a_mark_for_stopped_runs() {
        assert_eq!(Reach::parse("1713"), Some(Reach::Reached(1713)));
        assert_eq!(Reach::parse(">6164"), Some(Reach::Stopped(6164)));
        assert_eq!(Reach::parse(">"), None);
        assert_eq!(Reach::parse("12k"), None);
    }
}
