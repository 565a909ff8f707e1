use super::Starts;

#[test]
fn the_median_start_is_the_middle_fitness_ties_by_start() {
    assert_eq!(Starts::median_start(&[4.0]), 0);
    assert_eq!(Starts::median_start(&[3.0, 1.0, 2.0]), 2);
    assert_eq!(Starts::median_start(&[-1.0, 5.0, 0.5, 9.0, -3.0]), 2);
    // Equal fitness: the earlier start of the tied pair sits first, so the middle is fixed.
    assert_eq!(Starts::median_start(&[2.0, 2.0, 1.0]), 0);
    assert_eq!(Starts::median_start(&[1.0, 2.0, 2.0]), 1);
}

#[test]
fn counts_must_be_odd_and_phases_must_not_wrap() {
    let ok = |count, shift| Starts { count, shift }.validate().is_ok();
    assert!(ok(1, 1e-4) && ok(3, 1e-4) && ok(5, 0.2));
    assert!(!ok(0, 1e-4) && !ok(2, 1e-4) && !ok(4, 1e-4));
    assert!(!ok(3, 0.0) && !ok(3, -1e-4) && !ok(3, f64::NAN) && !ok(3, 0.5));
    let message = Starts {
        count: 2,
        shift: 1e-4,
    }
    .validate()
    .unwrap_err()
    .to_string();
    assert!(message.contains("starts.count"), "{message}");
}

#[test]
fn start_k_is_k_shifts_of_a_period_later() {
    let s = Starts {
        count: 3,
        shift: 0.25,
    };
    assert_eq!(s.phase(0), 0.0);
    assert!((s.phase(2) - std::f64::consts::PI).abs() < 1e-15);
}
