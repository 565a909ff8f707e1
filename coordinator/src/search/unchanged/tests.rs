use super::*;

#[test]
fn a_budget_takes_children_in_turn_from_each_island() {
    let mut keep = vec![vec![true; 3], vec![false, true, true], vec![true]];
    first_in_turn(&mut keep, 4);
    // In turn: island 0's first, island 2's first (island 1's first is not kept), then
    // island 0's and island 1's second.
    assert_eq!(
        keep,
        vec![
            vec![true, true, false],
            vec![false, true, false],
            vec![true]
        ]
    );
}

#[test]
fn a_budget_larger_than_the_epoch_keeps_every_marked_child() {
    let marked = vec![vec![true, false, true], vec![false, true]];
    let mut keep = marked.clone();
    first_in_turn(&mut keep, 3);
    assert_eq!(keep, marked);
    first_in_turn(&mut keep, u64::MAX);
    assert_eq!(keep, marked);
}

#[test]
fn the_first_n_in_turn_are_the_same_whatever_budget_cut_them() {
    // A replay knows only how many were evaluated: cutting at that count again must give
    // the same children.
    let marked = vec![
        vec![true, false, true, true],
        vec![true, true],
        vec![false, true],
    ];
    for left in 0..8 {
        let mut cut = marked.clone();
        first_in_turn(&mut cut, left);
        let n = cut.iter().flatten().filter(|&&k| k).count() as u64;
        let mut again = marked.clone();
        first_in_turn(&mut again, n);
        assert_eq!(again, cut, "left {left}");
    }
}

#[test]
fn an_epoch_of_copies_still_evaluates_its_first_child() {
    let mut keep = vec![vec![], vec![false, false], vec![false]];
    keep_at_least_one(&mut keep);
    assert_eq!(keep, vec![vec![], vec![true, false], vec![false]]);
    let mut some = vec![vec![false, true]];
    keep_at_least_one(&mut some);
    assert_eq!(some, vec![vec![false, true]]);
}
