//! Nudges added up by what they did to the error. The session-13 combination applies every nudge
//! that improved the design, and on the circular arc that overshoots in most epochs: nudges that
//! each improve the design often fix the same part of the profile error (docs/evolution.md,
//! session 37). A least-squares task says more than a fitness: its residuals, one per station
//! along the beam. A small change moves them, and the moves of changes to different points add
//! up about linearly, where their fitnesses do not. So each of an epoch's nudges is a measured
//! direction: its residuals less the base's. The model predicts the residuals of any set of
//! nudges applied together as the base's plus the sum of their directions, and a greedy forward
//! selection picks the set whose predicted error is lowest: first the fittest nudge (where the
//! model is exact), then at each step the nudge that lowers the predicted error most, until none
//! does. A nudge that overshoots what the chosen ones already fixed is left out; a nudge that did
//! not improve the design alone can come in, when it fixes what the others leave.
//!
//! Two nudges that move the same point cannot both be applied, so a nudge that touches a point
//! already chosen is passed over. The selection is a pure function of the epoch's genomes and
//! outcomes, so a replayed run rebuilds it bit for bit.

use amorph::genome::{GaussianPoint, Genome};

/// One of an epoch's nudges as the model sees it: its design and its residuals, station by
/// station as the base's.
pub struct Nudged<'a> {
    pub genome: &'a Genome,
    pub residuals: Vec<f64>,
}

/// The residual values of `nudge` where they line up with `base`'s, station for station (the same
/// positions to the bit), or `None`: a design whose surface misses a station the base has (or
/// has one more) is not a small change of it, and its direction means nothing.
pub fn aligned(base: &[[f64; 2]], nudge: &[[f64; 2]]) -> Option<Vec<f64>> {
    let lined_up = base.len() == nudge.len()
        && (base.iter().zip(nudge)).all(|(b, n)| b[0].to_bits() == n[0].to_bits());
    lined_up.then(|| nudge.iter().map(|n| n[1]).collect())
}

/// What a nudge changes of `base`: the indices of the points it moved and the points it
/// appended, or `None` when it has fewer points (it is not a nudge of `base`).
pub(super) fn changes<'a>(
    base: &Genome,
    nudge: &'a Genome,
) -> Option<(Vec<usize>, &'a [GaussianPoint])> {
    let n = base.points.len();
    if nudge.points.len() < n {
        return None;
    }
    let moved = (0..n)
        .filter(|&i| nudge.points[i] != base.points[i])
        .collect();
    Some((moved, &nudge.points[n..]))
}

pub(super) fn squared(residuals: impl Iterator<Item = f64>) -> f64 {
    residuals.map(|r| r * r).sum()
}

/// A design with its residuals, station by station.
#[derive(Clone, Copy)]
pub struct Measured<'a> {
    pub genome: &'a Genome,
    pub residuals: &'a [f64],
}

/// The nudges (indices into `nudges`, all bred from `base`) the model applies together onto
/// `onto` (`base` itself, or a design that descends from it: a rebased combination), in the order
/// it chose them. Each nudge's direction is its residuals less `base`'s; the predicted residuals
/// of a set are `onto`'s plus their directions. Each chosen nudge lowers the predicted error of
/// those before it the most; none moves a point another one (or `onto`, against `base`) moved,
/// none appends a point `onto` has, and their appended points fit `max_points`. Empty when no
/// nudge lowers `onto`'s error.
pub fn select(
    base: &Measured,
    onto: &Measured,
    nudges: &[Nudged],
    max_points: usize,
) -> Vec<usize> {
    let n = base.genome.points.len();
    let stations = base.residuals.len();
    let Some((onto_moved, onto_appended)) = changes(base.genome, onto.genome) else {
        return Vec::new();
    };
    if onto.residuals.len() != stations {
        return Vec::new();
    }
    let changes: Vec<Option<(Vec<usize>, &[GaussianPoint])>> = (nudges.iter())
        .map(|nudge| changes(base.genome, nudge.genome))
        .collect();
    let mut predicted = onto.residuals.to_vec();
    let mut error = squared(predicted.iter().copied());
    let mut moved = vec![false; n];
    for i in onto_moved {
        moved[i] = true;
    }
    let mut points = onto.genome.points.len();
    let mut chosen = Vec::new();
    loop {
        let mut pick: Option<(usize, f64)> = None;
        for (k, nudge) in nudges.iter().enumerate() {
            let Some((indices, appended)) = &changes[k] else {
                continue;
            };
            let fits = !chosen.contains(&k)
                && (indices.len() + appended.len()) > 0
                && indices.iter().all(|&i| !moved[i])
                && appended.iter().all(|p| !onto_appended.contains(p))
                && points + appended.len() <= max_points
                && nudge.residuals.len() == stations;
            if !fits {
                continue;
            }
            let with = squared(
                (predicted.iter().zip(&nudge.residuals).zip(base.residuals))
                    .map(|((p, r), b)| p + (r - b)),
            );
            // Strictly lower, the lowest index on a tie: a pure function of the epoch.
            if with < pick.map_or(error, |(_, e)| e) {
                pick = Some((k, with));
            }
        }
        let Some((k, with)) = pick else {
            return chosen;
        };
        let (indices, appended) = changes[k].as_ref().expect("a fitting nudge has changes");
        for (p, (r, b)) in
            (predicted.iter_mut()).zip(nudges[k].residuals.iter().zip(base.residuals))
        {
            *p += r - b;
        }
        for &i in indices {
            moved[i] = true;
        }
        points += appended.len();
        error = with;
        chosen.push(k);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::fixtures::points_at as genome;

    /// The selection onto the base itself.
    fn on_base(
        base: &Genome,
        residuals: &[f64],
        nudges: &[Nudged],
        max_points: usize,
    ) -> Vec<usize> {
        let base = Measured {
            genome: base,
            residuals,
        };
        select(&base, &base, nudges, max_points)
    }

    /// The base with point `i` moved.
    fn moved(base: &Genome, i: usize) -> Genome {
        crate::search::fixtures::moved(base, i, 0.01)
    }

    /// Nudges whose directions are orthogonal and each fix part of the error: the model takes
    /// every one that helps and leaves out the one that makes it worse, fittest first.
    #[test]
    fn orthogonal_fixes_are_all_taken_fittest_first() {
        let base = genome(&[0.1, 0.2, 0.3, 0.4]);
        let r0 = [1.0, 2.0, -1.0];
        let nudged: Vec<Genome> = (0..4).map(|i| moved(&base, i)).collect();
        let residuals = [
            vec![0.0, 2.0, -1.0], // fixes station 0: error 6 -> 5
            vec![1.0, 0.5, -1.0], // most of station 1: 6 -> 2.25
            vec![1.0, 2.0, -0.5], // half of station 2: 6 -> 5.25
            vec![1.0, 2.0, -3.0], // worse: 6 -> 14
        ];
        let nudges: Vec<Nudged> = (nudged.iter().zip(residuals))
            .map(|(genome, residuals)| Nudged { genome, residuals })
            .collect();
        assert_eq!(on_base(&base, &r0, &nudges, 10), vec![1, 0, 2]);
    }

    /// Two nudges that each fix all of one station's error overshoot together (the session-37
    /// failure): the model takes one of them.
    #[test]
    fn nudges_that_fix_the_same_error_are_not_stacked() {
        let base = genome(&[0.1, 0.2, 0.3]);
        let r0 = [2.0, 0.0];
        let (a, b) = (moved(&base, 0), moved(&base, 1));
        let nudges = [
            Nudged {
                genome: &a,
                residuals: vec![0.1, 0.0],
            },
            Nudged {
                genome: &b,
                residuals: vec![0.0, 0.0],
            },
        ];
        // Both: 2 - 1.9 - 2 = -1.9, worse than b alone.
        assert_eq!(on_base(&base, &r0, &nudges, 10), vec![1]);
    }

    /// A nudge that does not improve the design alone comes in when it fixes what the chosen one
    /// left, and a nudge that moves a point already moved is passed over.
    #[test]
    fn a_complement_comes_in_and_a_conflict_stays_out() {
        let base = genome(&[0.1, 0.2, 0.3]);
        let r0 = [1.0, 1.0];
        let a = moved(&base, 0);
        let mut conflicting = moved(&base, 0);
        conflicting.points[0].position[0] += 0.01;
        let c = moved(&base, 2);
        let nudges = [
            // Fixes station 0, spoils station 1 a little: 2 -> 1.21.
            Nudged {
                genome: &a,
                residuals: vec![0.0, 1.1],
            },
            // Alone 2 -> 2.26, worse than the base; after a it brings 1.21 -> 0.25.
            Nudged {
                genome: &c,
                residuals: vec![1.5, -0.1],
            },
            // Alone 1.7; after a it would bring 0.09, but it moves a's point.
            Nudged {
                genome: &conflicting,
                residuals: vec![1.3, -0.1],
            },
        ];
        assert_eq!(on_base(&base, &r0, &nudges, 10), vec![0, 1]);
    }

    /// Insertions append points: they stop at the limit, and a nudge with fewer points or with
    /// no change has no place in a combination.
    #[test]
    fn appended_points_stop_at_the_limit() {
        let base = genome(&[0.1, 0.2]);
        let one = genome(&[0.1, 0.2, 0.7]);
        let two = genome(&[0.1, 0.2, 0.8]);
        let shorter = genome(&[0.1]);
        let same = base.clone();
        let nudges = [
            Nudged {
                genome: &shorter,
                residuals: vec![0.0],
            },
            Nudged {
                genome: &same,
                residuals: vec![0.0],
            },
            Nudged {
                genome: &one,
                residuals: vec![0.5],
            },
            Nudged {
                genome: &two,
                residuals: vec![0.6],
            },
        ];
        assert_eq!(on_base(&base, &[1.0], &nudges, 3), vec![2]);
        assert_eq!(on_base(&base, &[1.0], &nudges, 4), vec![2, 3]);
    }

    /// Onto a newer design (a rebased combination) the prediction starts from its residuals:
    /// a nudge that fixed what it already fixed overshoots and stays out, a nudge that moved a
    /// point it moved or appended a point it has is passed over, and a single nudge counts.
    #[test]
    fn onto_a_newer_design_the_prediction_starts_from_it() {
        let base = genome(&[0.1, 0.2, 0.3]);
        let mut onto = moved(&base, 0);
        onto.points.push(genome(&[0.9]).points[0]);
        let r0 = [1.0, 1.0];
        let r_onto = [0.0, 1.0];
        let same_fix = moved(&base, 1);
        let other_fix = moved(&base, 2);
        let on_its_point = moved(&base, 0);
        let its_insertion = genome(&[0.1, 0.2, 0.3, 0.9]);
        let nudges = [
            // From the base it fixed station 0 as `onto` did: onto `onto` it overshoots to -1.
            Nudged {
                genome: &same_fix,
                residuals: vec![0.0, 1.0],
            },
            // Moves `onto`'s point; from `onto` it would fix station 1.
            Nudged {
                genome: &on_its_point,
                residuals: vec![1.0, 0.0],
            },
            // `onto`'s own insertion, the best of all from `onto`.
            Nudged {
                genome: &its_insertion,
                residuals: vec![1.0, -0.2],
            },
            // Halves station 1's error: 1 -> 0.25.
            Nudged {
                genome: &other_fix,
                residuals: vec![1.0, 0.5],
            },
        ];
        let measured = |genome, residuals| Measured { genome, residuals };
        let chosen = select(
            &measured(&base, &r0),
            &measured(&onto, &r_onto),
            &nudges,
            10,
        );
        assert_eq!(chosen, vec![3]);
        assert_eq!(on_base(&base, &r0, &nudges, 10), vec![0, 1]);
    }

    #[test]
    fn stations_line_up_by_position_or_not_at_all() {
        let base = [[0.5, 0.1], [1.0, 0.2]];
        assert_eq!(
            aligned(&base, &[[0.5, 0.3], [1.0, 0.4]]),
            Some(vec![0.3, 0.4])
        );
        assert_eq!(aligned(&base, &[[0.5, 0.3]]), None);
        assert_eq!(aligned(&base, &[[0.25, 0.3], [1.0, 0.4]]), None);
    }
}
