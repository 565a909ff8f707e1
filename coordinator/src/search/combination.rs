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
mod tests;
