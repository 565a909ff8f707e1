//! Nudges that add up. Crowding keeps at most one nudge of the best per epoch (the fittest one
//! replaces the best, the others then meet that new occupant and lose), so a climb made of nudges
//! would grow by one step per epoch whatever the epoch's size. Most nudges of one epoch move
//! different points of the same design, and their improvements often add up, so the improving
//! ones applied together are offered as a child of the next epoch: an epoch of many nudges can
//! advance the climb by many steps.
//!
//! The combination is a pure function of the epoch's genomes and outcomes, so a replayed run
//! rebuilds it bit for bit.

use amorph::genome::Genome;

/// `base` with the changes of every improving nudge applied: a moved point takes its value from
/// the fittest nudge that moved it (`improving` is fittest first), and a point a nudge appended
/// (an insertion) is appended, up to `max_points`. A nudge with fewer points than `base` is not
/// the base with points moved or appended, and is left out. `None` when fewer than two nudges
/// contribute: a single nudge's change is that nudge, already evaluated.
pub fn combine(base: &Genome, improving: &[&Genome], max_points: usize) -> Option<Genome> {
    let n = base.points.len();
    let mut combined = base.clone();
    let mut claimed = vec![false; n];
    let mut contributors = 0;
    for nudge in improving {
        if nudge.points.len() < n {
            continue;
        }
        let mut contributed = false;
        for (i, point) in nudge.points.iter().enumerate() {
            if i < n {
                if point != &base.points[i] && !claimed[i] {
                    combined.points[i] = *point;
                    claimed[i] = true;
                    contributed = true;
                }
            } else if combined.points.len() < max_points {
                combined.points.push(*point);
                contributed = true;
            }
        }
        contributors += usize::from(contributed);
    }
    (contributors >= 2).then_some(combined)
}

#[cfg(test)]
mod tests {
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
}
