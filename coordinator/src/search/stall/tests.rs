use super::*;

/// Improvement is relative to the best at the last progress, not to the previous epoch: many
/// small gains that add up to less than the threshold are one long stall.
#[test]
fn small_gains_that_do_not_add_up_are_a_stall() {
    let mut s = Stall::new();
    assert_eq!(s.observe(-10.0, 0.1), 0);
    assert_eq!(s.observe(-9.5, 0.1), 1); // 5 % better
    assert_eq!(s.observe(-9.1, 0.1), 2); // 9 % better than -10 in all
    assert_eq!(s.observe(-8.9, 0.1), 0); // 11 %: progress, from -8.9 on
    assert_eq!(s.observe(-8.9, 0.1), 1);
    assert_eq!(s.observe(-20.0, 0.1), 2); // worse is no progress either
}
