//! Study statistics against values worked by hand: medians with stopped runs (product limit),
//! P(faster), bootstrap intervals, the sign test, and the study CSV's parser.

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
    let text = format!("{RUNS_HEADER}\ncircular_arc,8,6,3,>5011,34\n\nstraight,1,50,2,2142,20\n");
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
