//! Pareto ranking of designs scored on several objectives, each minimized (a maximized objective
//! enters negated): dominance, the non-dominated fronts of a population (Deb et al., NSGA-II,
//! 2002), the crowding distance within a front, and the hypervolume a set of points dominates up
//! to a reference point (Zitzler & Thiele 1998).
//!
//! Everything here is a function of the points' values and order only, so a search built on it
//! stays deterministic: ties go to the lower index, and the hypervolume sums its slices in an
//! order fixed by the values, which makes it the same bits for any order of the same points.

use std::cmp::Ordering;

/// Whether `a` Pareto-dominates `b`: no worse in any objective and better in at least one.
pub fn dominates(a: &[f64], b: &[f64]) -> bool {
    debug_assert_eq!(a.len(), b.len(), "one value per objective");
    let mut better = false;
    for (x, y) in a.iter().zip(b) {
        if x > y {
            return false;
        }
        better |= x < y;
    }
    better
}

/// The non-dominated fronts of `points`, best first: front 0 holds the points no other point
/// dominates, front k those no point outside fronts 0..k dominates. Each front lists indices in
/// ascending order; together the fronts hold every index once. O(M N²) (Deb's fast sort).
pub fn fronts(points: &[&[f64]]) -> Vec<Vec<usize>> {
    let n = points.len();
    let mut dominated_by = vec![0usize; n];
    let mut dominating: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        for j in i + 1..n {
            if dominates(points[i], points[j]) {
                dominating[i].push(j);
                dominated_by[j] += 1;
            } else if dominates(points[j], points[i]) {
                dominating[j].push(i);
                dominated_by[i] += 1;
            }
        }
    }
    let mut current: Vec<usize> = (0..n).filter(|&i| dominated_by[i] == 0).collect();
    let mut fronts = Vec::new();
    while !current.is_empty() {
        let mut next = Vec::new();
        for &i in &current {
            for &j in &dominating[i] {
                dominated_by[j] -= 1;
                if dominated_by[j] == 0 {
                    next.push(j);
                }
            }
        }
        next.sort_unstable();
        fronts.push(std::mem::replace(&mut current, next));
    }
    fronts
}

/// The front each point belongs to (0 for the non-dominated ones), by [`fronts`].
pub fn front_ranks(points: &[&[f64]]) -> Vec<usize> {
    let mut ranks = vec![0; points.len()];
    for (rank, front) in fronts(points).iter().enumerate() {
        for &i in front {
            ranks[i] = rank;
        }
    }
    ranks
}

/// The crowding distance of each point of one front: for each objective, the gap between its two
/// neighbours along that objective divided by the front's range in it, summed over objectives.
/// The points at either end of an objective's range get infinity, so a front's extremes are kept
/// first; an objective in which the whole front is equal adds nothing.
pub fn crowding_distances(front: &[&[f64]]) -> Vec<f64> {
    let n = front.len();
    let mut distance = vec![0.0; n];
    let Some(objectives) = front.first().map(|p| p.len()) else {
        return distance;
    };
    let mut order: Vec<usize> = (0..n).collect();
    // `m` picks a coordinate of every point, not a point.
    #[allow(clippy::needless_range_loop)]
    for m in 0..objectives {
        order.sort_by(|&a, &b| front[a][m].total_cmp(&front[b][m]).then(a.cmp(&b)));
        let (low, high) = (front[order[0]][m], front[order[n - 1]][m]);
        distance[order[0]] = f64::INFINITY;
        distance[order[n - 1]] = f64::INFINITY;
        let range = high - low;
        // A front equal in this objective (or at infinity, a front of failures) adds nothing.
        if range.is_nan() || range <= 0.0 {
            continue;
        }
        for k in 1..n.saturating_sub(1) {
            let i = order[k];
            distance[i] += (front[order[k + 1]][m] - front[order[k - 1]][m]) / range;
        }
    }
    distance
}

/// The hypervolume that `points` dominate inside the box bounded above by `reference`: the
/// measure of every x with some point ≤ x ≤ reference. A point not strictly below the reference
/// in every objective adds nothing. Exact, by slicing along the last objective (O(N^(M−1) log N),
/// for the few objectives and the fronts of hundreds that a run has).
pub fn hypervolume(points: &[&[f64]], reference: &[f64]) -> f64 {
    let mut inside: Vec<&[f64]> = (points.iter().copied())
        .filter(|p| p.iter().zip(reference).all(|(x, r)| x < r))
        .collect();
    // Sorted by all values, so that the same points in any order give the same bits.
    inside.sort_by(|a, b| lexicographic(a, b));
    inside.dedup();
    volume(&inside, reference)
}

fn lexicographic(a: &[f64], b: &[f64]) -> Ordering {
    (a.iter().zip(b))
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(Ordering::Equal)
}

/// The hypervolume of points already inside the reference box, in lexicographic order.
fn volume(points: &[&[f64]], reference: &[f64]) -> f64 {
    let d = reference.len();
    if points.is_empty() {
        return 0.0;
    }
    if d == 1 {
        let best = points.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
        return reference[0] - best;
    }
    if d == 2 {
        // Sweep by the first objective: each point adds the strip between it and the lowest
        // second objective seen so far.
        let mut by_first = points.to_vec();
        by_first.sort_by(|a, b| lexicographic(a, b));
        let (mut area, mut ceiling) = (0.0, reference[1]);
        for p in by_first {
            if p[1] < ceiling {
                area += (reference[0] - p[0]) * (ceiling - p[1]);
                ceiling = p[1];
            }
        }
        return area;
    }
    // Slice along the last objective: between consecutive values of it, the points at or below
    // the slice's floor project to a (d − 1)-dimensional set.
    let last = d - 1;
    let mut levels: Vec<f64> = points.iter().map(|p| p[last]).collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    let mut total = 0.0;
    for (k, &floor) in levels.iter().enumerate() {
        let ceiling = levels.get(k + 1).copied().unwrap_or(reference[last]);
        let below: Vec<&[f64]> = (points.iter())
            .filter(|p| p[last] <= floor)
            .map(|p| &p[..last])
            .collect();
        total += volume(&below, &reference[..last]) * (ceiling - floor);
    }
    total
}

#[cfg(test)]
mod tests;
