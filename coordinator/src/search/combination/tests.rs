use super::*;
use amorph::genome::GaussianPoint;
use amorph::material::MaterialId;

fn point(x: f64) -> GaussianPoint {
    GaussianPoint {
        position: [x, 0.5, 0.5],
        density: 1.0,
        falloff: 0.1,
        material: MaterialId(0),
    }
}

fn genome(xs: &[f64]) -> Genome {
    Genome {
        points: xs.iter().map(|&x| point(x)).collect(),
    }
}

#[test]
fn nudges_of_different_points_are_all_applied() {
    let base = genome(&[0.1, 0.2, 0.3, 0.4]);
    let a = genome(&[0.15, 0.2, 0.3, 0.4]);
    let b = genome(&[0.1, 0.2, 0.35, 0.4]);
    let c = genome(&[0.1, 0.2, 0.3, 0.4, 0.9]);
    let combined = combine(&base, &[&a, &b, &c], 10).expect("three contributors");
    assert_eq!(combined, genome(&[0.15, 0.2, 0.35, 0.4, 0.9]));
}

#[test]
fn a_point_two_nudges_moved_takes_the_fittest_nudges_value() {
    let base = genome(&[0.1, 0.2]);
    let fittest = genome(&[0.11, 0.2]);
    let other = genome(&[0.12, 0.25]);
    let combined = combine(&base, &[&fittest, &other], 10).expect("two contributors");
    assert_eq!(combined, genome(&[0.11, 0.25]));
    assert_eq!(
        combine(&base, &[&other, &fittest], 10),
        None,
        "the fittest-first nudge covers every point the other moved"
    );
}

#[test]
fn one_contributor_is_no_combination() {
    let base = genome(&[0.1, 0.2]);
    let a = genome(&[0.11, 0.2]);
    assert_eq!(combine(&base, &[&a], 10), None);
    assert_eq!(
        combine(&base, &[&a, &base], 10),
        None,
        "an unchanged copy adds nothing"
    );
    assert_eq!(combine(&base, &[], 10), None);
}

#[test]
fn appended_points_stop_at_the_limit_and_shorter_genomes_are_left_out() {
    let base = genome(&[0.1, 0.2]);
    let moved = genome(&[0.15, 0.2]);
    let a = genome(&[0.1, 0.2, 0.7]);
    let b = genome(&[0.1, 0.2, 0.8]);
    let shorter = genome(&[0.5]);
    let combined = combine(&base, &[&moved, &a, &shorter, &b], 3).expect("two contributors");
    assert_eq!(
        combined,
        genome(&[0.15, 0.2, 0.7]),
        "the second insertion would pass 3 points"
    );
    assert_eq!(
        combine(&base, &[&a, &b], 3),
        None,
        "only one insertion fits"
    );
    let combined = combine(&base, &[&a, &b], 4).expect("both fit");
    assert_eq!(combined, genome(&[0.1, 0.2, 0.7, 0.8]));
}
