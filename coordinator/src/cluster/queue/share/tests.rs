use super::*;

#[test]
fn max_min_gives_small_demands_in_full_and_splits_the_rest_evenly() {
    assert_eq!(max_min(48, &[256, 1]), [47, 1]);
    assert_eq!(max_min(48, &[256, 256]), [24, 24]);
    assert_eq!(max_min(10, &[3, 100, 100]), [3, 4, 3]);
    assert_eq!(max_min(5, &[1, 1]), [1, 1]);
    assert_eq!(max_min(0, &[4, 4]), [0, 0]);
    // Rounded up: never less than an even split.
    assert_eq!(max_min(5, &[9, 9]), [3, 2]);
}

#[test]
fn the_lifetime_follows_the_median_within_its_bounds() {
    let rules = QueueRules {
        lease: Duration::from_secs(10),
        max_lease: Duration::from_secs(600),
        ..QueueRules::default()
    };
    let ms = |v: &[u64]| {
        let mut times = LeaseTimes::default();
        let t0 = Instant::now();
        for &m in v {
            times.measure(t0, t0 + Duration::from_millis(m));
        }
        times.median
    };
    assert_eq!(lifetime(ms(&[5000; 7]), &rules), rules.max_lease, "too few");
    assert_eq!(lifetime(ms(&[40; 8]), &rules), rules.lease, "floor");
    // Median 5 s, which three slow outliers do not move: 40 s.
    let mixed = ms(&[
        5000, 5000, 5000, 5000, 5000, 9_000_000, 9_000_000, 9_000_000,
    ]);
    assert_eq!(lifetime(mixed, &rules), Duration::from_secs(40));
    assert_eq!(
        lifetime(ms(&[200_000; 8]), &rules),
        rules.max_lease,
        "ceiling"
    );
}
