use super::*;

#[test]
fn switches_after_the_configured_stall() {
    let schedule = ResolutionSchedule {
        levels: vec![[1, 2, 1], [2, 4, 2]],
        stall_epochs: 3,
        min_improvement: 0.1,
        latest_switch: vec![],
        stall_on_finest: false,
    };
    let mut s = ResolutionState::new();
    assert!(!s.observe(-10.0, 10, &schedule));
    assert!(!s.observe(-5.0, 20, &schedule)); // progress
    assert!(!s.observe(-4.8, 30, &schedule)); // under 10 %: stall 1
    assert!(!s.observe(-4.7, 40, &schedule)); // stall 2
    assert!(s.observe(-4.7, 50, &schedule)); // stall 3: switch
    assert_eq!(s.level, 1);
    for _ in 0..10 {
        assert!(!s.observe(-1.0, 60, &schedule), "no level beyond the last");
    }
}

/// A level that keeps improving never stalls; `latest_switch` moves on anyway, once per level
/// and at the first epoch that reaches the count, and never past the last level.
#[test]
fn a_level_that_keeps_improving_gives_way_at_its_latest_switch() {
    let schedule = ResolutionSchedule {
        levels: vec![[1, 2, 1], [2, 4, 2], [3, 6, 3]],
        stall_epochs: 3,
        min_improvement: 0.01,
        latest_switch: vec![100, 250],
        stall_on_finest: false,
    };
    let mut s = ResolutionState::new();
    let mut best = -100.0;
    let mut switched_at = Vec::new();
    for evaluations in (10..=400).step_by(10) {
        best *= 0.9; // 10 % better every epoch: never a stall
        if s.observe(best, evaluations, &schedule) {
            switched_at.push(evaluations);
        }
    }
    assert_eq!(switched_at, [100, 250]);
    assert_eq!(s.level, 2);
}

#[test]
fn latest_switch_needs_one_increasing_count_per_coarse_level() {
    let schedule = |latest_switch: Vec<u64>| ResolutionSchedule {
        levels: vec![[1, 2, 1], [2, 4, 2], [3, 6, 3]],
        stall_epochs: 3,
        min_improvement: 0.01,
        latest_switch,
        stall_on_finest: false,
    };
    assert!(schedule(vec![]).validate().is_ok());
    assert!(schedule(vec![100, 200]).validate().is_ok());
    let err = schedule(vec![100]).validate().unwrap_err();
    assert!(err.starts_with("resolution.latest_switch lists 1"), "{err}");
    let err = schedule(vec![200, 200]).validate().unwrap_err();
    assert!(
        err.starts_with("resolution.latest_switch[1] = 200"),
        "{err}"
    );
}
