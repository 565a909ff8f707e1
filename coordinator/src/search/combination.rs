//! Nudges that add up. Crowding keeps at most one nudge of the best per epoch (the fittest one
//! replaces the best, the others then meet that new occupant and lose), so a climb made of nudges
//! grows by one step per epoch whatever the epoch's size (docs/evolution.md, sessions 10 and 12).
//! Most nudges of one epoch move different points of the same design, and their improvements
//! often add up: the improving ones, applied together, can be better than the best of them alone.
//! That combined design is offered as a child of the next epoch, so an epoch of many nudges can
//! advance the climb by many steps. Often they do not add up: nudges that fix the same part of
//! the error overshoot together. On the circular arc at 12x40x12 the combination of all of them
//! beat every nudge of its epoch in a fifth to a third of the epochs (session 37), so a run may
//! offer the fittest half, quarter, ... as well (`combinations`).
//!
//! The combination is a pure function of the epoch's genomes and outcomes, so a replayed run
//! rebuilds it bit for bit.

use amorph::genome::{Genome, GenomeLimits};
use serde::{Deserialize, Serialize};

/// Which of an epoch's nudges are added up (`[search.local_search]` `combine_by`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CombineBy {
    /// Every nudge that beat the design it started from, fittest first (session 13).
    #[default]
    Fitness,
    /// The nudges a linear model of the task's residuals picks (`search::residual_model`); a
    /// task whose fitness is not a sum of squared residuals cannot use it.
    Residuals,
    /// The same model's least-squares step along every nudge, each taken as far as it helps
    /// within `reach` (`search::least_squares`); a task without residuals cannot use it.
    LeastSquares,
}

impl CombineBy {
    /// Whether the rule reads the task's residuals.
    pub fn needs_residuals(self) -> bool {
        self != CombineBy::Fitness
    }

    /// The rule as the config writes it.
    pub fn key(self) -> &'static str {
        match self {
            CombineBy::Fitness => "fitness",
            CombineBy::Residuals => "residuals",
            CombineBy::LeastSquares => "least_squares",
        }
    }
}

/// How an epoch's nudges are added up (`[search.local_search]` `combine`, `combine_by`,
/// `combinations`, `rebase`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Combining {
    /// Which nudges: the improving ones, the residual model's pick, or its least-squares step.
    pub by: CombineBy,
    /// The genome's ranges: appended points stop at its point limit, and a least-squares step
    /// stays in its parameter ranges.
    pub limits: GenomeLimits,
    /// With `LeastSquares`: how far from zero a nudge's coefficient may go.
    pub reach: f64,
    /// How many combined designs to offer: all the improving nudges, then the fittest half, the
    /// fittest quarter, and so on. Nudges of one region often fix the same part of the error, so
    /// all of them together overshoot where fewer would not (docs/evolution.md, session 37).
    pub combinations: usize,
    /// Build on the design that holds the nudges' slot after the epoch instead of the one they
    /// started from. When last epoch's combination wins, this epoch's nudges (bred before it was
    /// judged) otherwise add up on a design already beaten.
    pub rebase: bool,
}

/// The `base` design with the changes of every improving nudge applied, on `onto` (usually `base`
/// itself): a moved point takes its value from the fittest nudge that moved it (`improving` is
/// fittest first), and a point a nudge appended (an insertion) is appended, up to `max_points`. A
/// nudge that is not the base with points moved or appended (it has fewer points) is left out.
/// The changes are read against `base`, so on another design `onto` keeps every point where it
/// differs from `base` (its own accepted change wins) and every point it already appended. `None`
/// when `onto` has fewer points than `base` (it is not a descendant, so the changes have no
/// place), when nothing changes `onto`, or when `onto` is `base` and fewer than two nudges
/// contribute (a single nudge's change is that nudge, already evaluated).
pub fn combine_onto(
    base: &Genome,
    onto: &Genome,
    improving: &[&Genome],
    max_points: usize,
) -> Option<Genome> {
    let n = base.points.len();
    if onto.points.len() < n {
        return None;
    }
    let mut combined = onto.clone();
    let mut claimed = vec![false; n];
    let mut contributors = 0;
    for nudge in improving {
        if nudge.points.len() < n {
            continue;
        }
        let mut contributed = false;
        for (i, point) in nudge.points.iter().enumerate() {
            if i < n {
                if point != &base.points[i] && !claimed[i] && onto.points[i] == base.points[i] {
                    combined.points[i] = *point;
                    claimed[i] = true;
                    contributed = true;
                }
            } else if combined.points.len() < max_points && !onto.points[n..].contains(point) {
                combined.points.push(*point);
                contributed = true;
            }
        }
        contributors += usize::from(contributed);
    }
    let new = if onto == base {
        contributors >= 2
    } else {
        contributors >= 1 && combined != *onto
    };
    new.then_some(combined)
}

/// The combined designs of one epoch's improving nudges (fittest first), at most
/// `combining.combinations` of them, distinct: all of them, then the fittest half, quarter, ...
/// down to one, each through [`combine_onto`] (`onto` is `base` unless `rebase`).
pub fn combinations(
    base: &Genome,
    onto: &Genome,
    improving: &[&Genome],
    combining: &Combining,
) -> Vec<Genome> {
    let onto = if combining.rebase { onto } else { base };
    let mut sizes = Vec::new();
    let mut size = improving.len();
    while size > 0 && sizes.len() < combining.combinations {
        sizes.push(size);
        if size == 1 {
            break;
        }
        size = size.div_ceil(2);
    }
    let mut offered: Vec<Genome> = Vec::new();
    for size in sizes {
        if let Some(genome) =
            combine_onto(base, onto, &improving[..size], combining.limits.max_points)
            && !offered.contains(&genome)
        {
            offered.push(genome);
        }
    }
    offered
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
        let combined = combine_onto(&base, &base, &[&a, &b, &c], 10).expect("three contributors");
        assert_eq!(combined, genome(&[0.15, 0.2, 0.35, 0.4, 0.9]));
    }

    #[test]
    fn a_point_two_nudges_moved_takes_the_fittest_nudges_value() {
        let base = genome(&[0.1, 0.2]);
        let fittest = genome(&[0.11, 0.2]);
        let other = genome(&[0.12, 0.25]);
        let combined =
            combine_onto(&base, &base, &[&fittest, &other], 10).expect("two contributors");
        assert_eq!(combined, genome(&[0.11, 0.25]));
        // In the other order the other nudge's value wins point 0.
        let combined = combine_onto(&base, &base, &[&other, &fittest], 10);
        assert_eq!(
            combined, None,
            "the fittest-first nudge covers every point the other moved"
        );
    }

    #[test]
    fn one_contributor_is_no_combination() {
        let base = genome(&[0.1, 0.2]);
        let a = genome(&[0.11, 0.2]);
        assert_eq!(combine_onto(&base, &base, &[&a], 10), None);
        assert_eq!(
            combine_onto(&base, &base, &[&a, &base], 10),
            None,
            "an unchanged copy adds nothing"
        );
        assert_eq!(combine_onto(&base, &base, &[], 10), None);
    }

    #[test]
    fn appended_points_stop_at_the_limit_and_shorter_genomes_are_left_out() {
        let base = genome(&[0.1, 0.2]);
        let moved = genome(&[0.15, 0.2]);
        let a = genome(&[0.1, 0.2, 0.7]);
        let b = genome(&[0.1, 0.2, 0.8]);
        let shorter = genome(&[0.5]);
        let combined =
            combine_onto(&base, &base, &[&moved, &a, &shorter, &b], 3).expect("two contributors");
        assert_eq!(
            combined,
            genome(&[0.15, 0.2, 0.7]),
            "the second insertion would pass 3 points"
        );
        assert_eq!(
            combine_onto(&base, &base, &[&a, &b], 3),
            None,
            "only one insertion fits"
        );
        let combined = combine_onto(&base, &base, &[&a, &b], 4).expect("both fit");
        assert_eq!(combined, genome(&[0.1, 0.2, 0.7, 0.8]));
    }

    fn combining(combinations: usize, rebase: bool) -> Combining {
        Combining {
            by: CombineBy::Fitness,
            limits: GenomeLimits {
                max_points: 10,
                ..GenomeLimits::default()
            },
            reach: 1.0,
            combinations,
            rebase,
        }
    }

    /// On a design that moved on, the nudges' changes land where it still has the old point; a
    /// point it changed itself, or a point it already appended, is left as it is.
    #[test]
    fn on_a_newer_design_its_own_changes_win_and_nothing_is_appended_twice() {
        let base = genome(&[0.1, 0.2, 0.3]);
        let inserted = genome(&[0.1, 0.2, 0.3, 0.9]);
        let moved = genome(&[0.1, 0.25, 0.3]);
        let conflicting = genome(&[0.12, 0.2, 0.3]);
        // The design after the epoch: point 0 moved by last epoch's combination, and the insertion
        // of this epoch already appended (it won the slot).
        let onto = genome(&[0.11, 0.2, 0.3, 0.9]);
        let improving = [&inserted, &moved, &conflicting];
        let combined = combine_onto(&base, &onto, &improving, 10).expect("one new change");
        assert_eq!(combined, genome(&[0.11, 0.25, 0.3, 0.9]));
        // A single contributor is new on a newer design, not on the base itself.
        assert_eq!(
            combine_onto(&base, &onto, &[&moved], 10),
            Some(genome(&[0.11, 0.25, 0.3, 0.9]))
        );
        assert_eq!(combine_onto(&base, &base, &[&moved], 10), None);
        // Nothing new: every change is already in the design.
        assert_eq!(
            combine_onto(&base, &onto, &[&inserted, &conflicting], 10),
            None
        );
        // A design with fewer points than the base is not its descendant.
        assert_eq!(
            combine_onto(&base, &genome(&[0.1, 0.2]), &improving, 10),
            None
        );
    }

    /// The offered designs are the improving nudges' prefixes, fittest first, halving: all, the
    /// fittest half, quarter, ..., distinct and at most `combinations`; one combination on the
    /// base is the session-13 rule.
    #[test]
    fn combinations_are_the_fittest_prefixes_halving() {
        let base = genome(&[0.1, 0.2, 0.3, 0.4, 0.5]);
        let nudged = |i: usize| {
            let mut g = base.clone();
            g.points[i].position[0] += 0.01;
            g
        };
        let nudges: Vec<Genome> = (0..5).map(nudged).collect();
        let improving: Vec<&Genome> = nudges.iter().collect();
        let prefix =
            |k: usize| combine_onto(&base, &base, &improving[..k], 10).expect("two or more");
        // 5, 3, 2, then 1, which on the base is no combination.
        let offered = combinations(&base, &base, &improving, &combining(4, false));
        assert_eq!(offered, vec![prefix(5), prefix(3), prefix(2)]);
        assert_eq!(
            combinations(&base, &base, &improving, &combining(2, false)),
            vec![prefix(5), prefix(3)]
        );
        assert_eq!(
            combinations(&base, &base, &improving, &combining(1, false)),
            vec![prefix(5)],
            "one combination is the old rule"
        );
        // Without `rebase` the design after the epoch is ignored; with it, the prefixes land on it
        // and the single fittest nudge counts.
        let onto = nudges[0].clone();
        assert_eq!(
            combinations(&base, &onto, &improving, &combining(4, false)),
            vec![prefix(5), prefix(3), prefix(2)]
        );
        let rebased = combinations(&base, &onto, &improving, &combining(4, true));
        assert_eq!(
            rebased,
            vec![prefix(5), prefix(3), prefix(2)],
            "the fittest is the design itself"
        );
        let onto = genome(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.8]);
        let rebased = combinations(&base, &onto, &improving, &combining(4, true));
        assert_eq!(
            rebased.len(),
            4,
            "5, 3, 2 and the fittest alone, all new on this design"
        );
        assert_eq!(
            rebased[3].points,
            [nudged(0).points, vec![point(0.8)]].concat()
        );
    }
}
