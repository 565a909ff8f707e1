//! The variation keys' validation, and how they count and place an epoch's nudges.

use super::*;

fn one_fifth() -> StepAdaptation {
    StepAdaptation {
        rule: StepRule::OneFifth,
        ..Default::default()
    }
}

#[test]
fn the_fixed_rule_never_changes_the_step() {
    let fixed = StepAdaptation::default();
    assert_eq!(fixed.next_scale(1.0, 50, 50), 1.0);
    assert_eq!(fixed.next_scale(1.0, 0, 50), 1.0);
}

#[test]
fn one_fifth_grows_above_a_fifth_shrinks_below_and_holds_at_it() {
    let a = one_fifth();
    assert_eq!(a.next_scale(1.0, 11, 50), 1.2);
    assert_eq!(a.next_scale(1.0, 9, 50), 1.0 / 1.2);
    assert_eq!(a.next_scale(1.0, 10, 50), 1.0);
    assert_eq!(a.next_scale(0.7, 0, 0), 0.7, "no children, no evidence");
}

#[test]
fn one_fifth_stays_within_its_bounds() {
    let a = one_fifth();
    let mut s = 1.0;
    for _ in 0..100 {
        s = a.next_scale(s, 0, 50);
    }
    assert_eq!(s, a.min_scale);
    for _ in 0..100 {
        s = a.next_scale(s, 50, 50);
    }
    assert_eq!(s, a.max_scale);
}

#[test]
fn nudges_round_to_the_nearest_child() {
    let l = LocalSearchParams {
        fraction: 0.2,
        ..Default::default()
    };
    assert_eq!(l.nudges(50), 10);
    assert_eq!(l.nudges(3), 1);
    assert_eq!(LocalSearchParams::default().nudges(50), 0);
}

#[test]
fn an_epochs_nudges_are_its_share_whatever_the_island_count() {
    let each = LocalSearchParams {
        fraction: 0.5,
        shared: true,
        ..Default::default()
    };
    let l = LocalSearchParams {
        per_epoch: true,
        ..each.clone()
    };
    // Per island, 16 islands of 3 round 1.5 up to 2 each: 32 of 48.
    assert_eq!(each.nudges_per_island(&[3; 16]).iter().sum::<usize>(), 32);
    for islands in [1, 2, 4, 8, 16] {
        let counts = vec![48 / islands; islands];
        let nudges = l.nudges_per_island(&counts);
        assert_eq!(nudges.iter().sum::<usize>(), 24, "{islands} islands");
        let (lo, hi) = (nudges.iter().min().unwrap(), nudges.iter().max().unwrap());
        assert!(hi - lo <= 1, "{nudges:?}");
    }
    // A budget-cut island takes what it can; the others take the rest of the epoch's share.
    assert_eq!(l.nudges_per_island(&[3, 0, 1, 3]), vec![2, 0, 1, 1]);
    assert_eq!(l.nudges_per_island(&[0, 0]), vec![0, 0]);
}

#[test]
fn per_epoch_needs_a_shared_climb() {
    let mut v = Variation::default();
    v.local_search.per_epoch = true;
    let err = v.validate().unwrap_err();
    assert!(err.contains("search.local_search.per_epoch"), "{err}");
    v.local_search.shared = true;
    v.validate().unwrap();
}

#[test]
fn the_finest_fraction_acts_only_at_the_finest_level() {
    let l = LocalSearchParams {
        fraction: 0.5,
        finest_fraction: Some(1.0),
        ..Default::default()
    };
    assert_eq!(l.at_level(false).nudges(48), 24);
    assert_eq!(l.at_level(true).nudges(48), 48);
    let unset = LocalSearchParams {
        fraction: 0.5,
        ..Default::default()
    };
    assert_eq!(
        unset.at_level(true),
        unset,
        "unset, the finest level breeds as the others"
    );
    let mut v = Variation::default();
    v.local_search.finest_fraction = Some(1.5);
    let err = v.validate().unwrap_err();
    assert!(err.contains("search.local_search.finest_fraction"), "{err}");
}

#[test]
fn each_bad_field_is_named() {
    let mut v = Variation::default();
    assert!(v.validate().is_ok());
    v.crossover.axis = 3;
    assert!(v.validate().unwrap_err().contains("search.crossover.axis"));
    v = Variation::default();
    v.step_adaptation.factor = 1.0;
    assert!(
        v.validate()
            .unwrap_err()
            .contains("search.step_adaptation.factor")
    );
    v = Variation::default();
    v.local_search.combine = true;
    v.local_search.combinations = 0;
    assert!(
        v.validate()
            .unwrap_err()
            .contains("search.local_search.combinations must be between 1 and 16")
    );
    v.local_search.combinations = 3;
    assert!(v.validate().is_ok());
    v.local_search.combine = false;
    assert!(
        v.validate()
            .unwrap_err()
            .contains("need search.local_search.combine = true")
    );
    v = Variation::default();
    v.local_search.rebase = true;
    assert!(v.validate().unwrap_err().contains("rebase need"));
    v = Variation::default();
    v.local_search.combine_by = crate::search::CombineBy::Residuals;
    assert!(v.validate().unwrap_err().contains("combine_by"));
    v.local_search.combine = true;
    assert!(v.validate().is_ok());
    // `reach` is the least-squares step's, and a coefficient stays within a few nudges.
    v.local_search.reach = 2.0;
    assert!(v.validate().unwrap_err().contains("reach needs"));
    v.local_search.combine_by = crate::search::CombineBy::LeastSquares;
    assert!(v.validate().is_ok());
    for bad in [0.0, -1.0, 9.0, f64::NAN, f64::INFINITY] {
        v.local_search.reach = bad;
        assert!(
            v.validate()
                .unwrap_err()
                .contains("search.local_search.reach must be")
        );
    }
    v = Variation::default();
    v.local_search.fraction = f64::NAN;
    assert!(
        v.validate()
            .unwrap_err()
            .contains("search.local_search.fraction")
    );
}

#[test]
fn without_a_spread_the_step_is_fixed_and_draws_nothing() {
    use rand::{RngExt, SeedableRng};
    let params = LocalSearchParams::default();
    let mut a = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut b = a.clone();
    assert_eq!(params.nudge_step(&mut a), params.step);
    assert_eq!(
        a.random::<u64>(),
        b.random::<u64>(),
        "a spread of 0 must leave the stream where it was, so earlier configs breed as before"
    );
}

#[test]
fn a_spread_scales_the_step_log_uniformly_within_its_octaves() {
    use rand::SeedableRng;
    let params = LocalSearchParams {
        step_spread: 2.0,
        ..Default::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let n = 20_000;
    let octaves: Vec<f64> = (0..n)
        .map(|_| (params.nudge_step(&mut rng) / params.step).log2())
        .collect();
    assert!(octaves.iter().all(|o| (-2.0..=2.0).contains(o)));
    // Uniform on [-2, 2]: each quarter holds a quarter of the draws. Five binomial standard
    // deviations (sqrt(n p (1 - p)) / n = 0.0031) is a bound a correct draw fails once in ~10^6.
    for q in 0..4 {
        let lo = -2.0 + q as f64;
        let share = octaves.iter().filter(|&&o| o >= lo && o < lo + 1.0).count() as f64 / n as f64;
        assert!((share - 0.25).abs() < 5.0 * 0.0031, "quarter {q}: {share}");
    }
}

#[test]
fn a_spread_beyond_six_octaves_or_negative_is_named() {
    for bad in [-0.5, 6.5, f64::NAN] {
        let mut v = Variation::default();
        v.local_search.step_spread = bad;
        let err = v.validate().unwrap_err();
        assert!(
            err.contains("search.local_search.step_spread"),
            "{bad}: {err}"
        );
    }
    let mut v = Variation::default();
    v.local_search.step_spread = 6.0;
    assert!(v.validate().is_ok());
}
