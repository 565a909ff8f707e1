use super::median;

#[test]
fn median_ignores_a_one_off_jump() {
    assert_eq!(median(vec![]), 0.0);
    assert_eq!(median(vec![3.0]), 3.0);
    assert_eq!(median(vec![0.1, 9.0, 0.3]), 0.3);
    assert_eq!(median(vec![0.2, 0.1, 6.0, 0.3]), 0.25);
}
