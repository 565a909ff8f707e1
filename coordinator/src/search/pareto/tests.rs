use super::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn refs(points: &[Vec<f64>]) -> Vec<&[f64]> {
    points.iter().map(Vec::as_slice).collect()
}

#[test]
fn dominance_needs_no_worse_everywhere_and_better_somewhere() {
    assert!(dominates(&[1.0, 2.0], &[1.0, 3.0]));
    assert!(dominates(&[0.0, 0.0, 0.0], &[1.0, 1.0, 1.0]));
    assert!(!dominates(&[1.0, 2.0], &[1.0, 2.0]), "equal points");
    assert!(!dominates(&[1.0, 3.0], &[2.0, 2.0]), "a trade-off");
    assert!(!dominates(&[2.0, 2.0], &[1.0, 3.0]), "a trade-off");
    assert!(!dominates(&[1.0, 3.0], &[1.0, 2.0]));
}

/// Three layers by hand: (0, 3), (1, 1), (3, 0) trade off; (2, 2) and (1, 3) are each dominated
/// only by the first layer; (3, 3) by the second too.
#[test]
fn fronts_peel_layer_by_layer() {
    let points = vec![
        vec![2.0, 2.0],
        vec![0.0, 3.0],
        vec![3.0, 3.0],
        vec![1.0, 1.0],
        vec![1.0, 3.0],
        vec![3.0, 0.0],
    ];
    assert_eq!(
        fronts(&refs(&points)),
        vec![vec![1, 3, 5], vec![0, 4], vec![2]]
    );
    assert_eq!(front_ranks(&refs(&points)), vec![1, 0, 2, 0, 1, 0]);
    assert!(fronts(&[]).is_empty());
}

/// On random clouds: no point is dominated by one of its own or of a later front, every point
/// past the first front is dominated by one of the front before it, and each index is in one
/// front.
#[test]
fn fronts_are_the_non_dominated_layers_of_random_clouds() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for objectives in 2..=4 {
        // Values on a coarse grid, so that ties and equal points occur.
        let points: Vec<Vec<f64>> = (0..60)
            .map(|_| {
                (0..objectives)
                    .map(|_| f64::from(rng.random_range(0..6u8)))
                    .collect()
            })
            .collect();
        let points = refs(&points);
        let fronts = fronts(&points);
        let mut seen: Vec<usize> = fronts.concat();
        seen.sort_unstable();
        assert_eq!(seen, (0..points.len()).collect::<Vec<_>>());
        for (k, front) in fronts.iter().enumerate() {
            for &i in front {
                for later in &fronts[k..] {
                    assert!(later.iter().all(|&j| !dominates(points[j], points[i])));
                }
                if k > 0 {
                    assert!(
                        fronts[k - 1]
                            .iter()
                            .any(|&j| dominates(points[j], points[i]))
                    );
                }
            }
        }
    }
}

/// Deb's formula by hand on four points of a line: the ends are infinite, the two inside get
/// (2 − 0)/4 + (4 − 1)/4 = 1.25 and (4 − 1)/4 + (2 − 0)/4 = 1.25.
#[test]
fn crowding_distance_by_hand() {
    let front = vec![
        vec![1.0, 2.0],
        vec![0.0, 4.0],
        vec![4.0, 0.0],
        vec![2.0, 1.0],
    ];
    assert_eq!(
        crowding_distances(&refs(&front)),
        vec![1.25, f64::INFINITY, f64::INFINITY, 1.25]
    );
    // A front equal in one objective: that objective adds nothing, and the lower index is the
    // end of the range on a tie.
    let flat = vec![vec![1.0, 5.0], vec![2.0, 5.0], vec![3.0, 5.0]];
    assert_eq!(
        crowding_distances(&refs(&flat)),
        vec![f64::INFINITY, 1.0, f64::INFINITY]
    );
    assert_eq!(crowding_distances(&[&[1.0, 1.0]]), vec![f64::INFINITY]);
    assert!(crowding_distances(&[]).is_empty());
}

#[test]
fn the_hypervolume_of_one_point_is_its_box() {
    assert_eq!(hypervolume(&[&[1.0, 2.0]], &[4.0, 4.0]), 6.0);
    assert_eq!(hypervolume(&[&[1.0, 2.0, 3.0]], &[2.0, 4.0, 7.0]), 8.0);
    assert_eq!(
        hypervolume(&[&[5.0, 0.0]], &[4.0, 4.0]),
        0.0,
        "outside the box"
    );
    assert_eq!(hypervolume(&[&[4.0, 0.0]], &[4.0, 4.0]), 0.0, "on its edge");
    assert_eq!(hypervolume(&[], &[1.0, 1.0]), 0.0);
}

/// The measure of the union by brute force: cut the box on every coordinate any point or the
/// reference has, and add up the cells whose lower corner some point dominates (or equals).
fn brute_force(points: &[&[f64]], reference: &[f64]) -> f64 {
    let d = reference.len();
    let cuts: Vec<Vec<f64>> = (0..d)
        .map(|m| {
            let mut c: Vec<f64> = points
                .iter()
                .map(|p| p[m])
                .filter(|&x| x < reference[m])
                .chain([reference[m]])
                .collect();
            c.sort_by(f64::total_cmp);
            c.dedup();
            c
        })
        .collect();
    let mut total = 0.0;
    let mut cell = vec![0usize; d];
    'cells: loop {
        let corner: Vec<f64> = (0..d).map(|m| cuts[m][cell[m]]).collect();
        let inside = cell.iter().enumerate().all(|(m, &c)| c + 1 < cuts[m].len());
        if inside
            && points
                .iter()
                .any(|p| p.iter().zip(&corner).all(|(x, c)| x <= c))
        {
            total += (0..d)
                .map(|m| cuts[m][cell[m] + 1] - cuts[m][cell[m]])
                .product::<f64>();
        }
        for m in 0..d {
            cell[m] += 1;
            if cell[m] < cuts[m].len() {
                continue 'cells;
            }
            cell[m] = 0;
        }
        break;
    }
    total
}

/// Against the brute-force union on random clouds of 1 to 12 points in 2 to 4 objectives, some
/// outside the box, some repeated; and the same bits for the points in reverse order.
#[test]
fn the_hypervolume_is_the_measure_of_the_dominated_union() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for objectives in 2..=4 {
        let reference = vec![1.0; objectives];
        for _ in 0..40 {
            let n = rng.random_range(1..=12);
            let mut points: Vec<Vec<f64>> = (0..n)
                .map(|_| {
                    (0..objectives)
                        .map(|_| rng.random_range(0.0..1.2))
                        .collect()
                })
                .collect();
            points.push(points[0].clone());
            let points = refs(&points);
            let exact = hypervolume(&points, &reference);
            let brute = brute_force(&points, &reference);
            assert!(
                (exact - brute).abs() <= 1e-12 * brute.max(1.0),
                "{objectives} objectives, {n} points: {exact} against {brute}"
            );
            let reversed: Vec<&[f64]> = points.iter().rev().copied().collect();
            assert_eq!(
                hypervolume(&reversed, &reference).to_bits(),
                exact.to_bits()
            );
        }
    }
}

/// Adding a dominated point changes nothing; adding a point outside the current union adds
/// exactly the volume only it covers (a box, when it dominates every point's box corner).
#[test]
fn a_dominated_point_adds_no_hypervolume() {
    let front = vec![vec![0.2, 0.7], vec![0.5, 0.4], vec![0.8, 0.1]];
    let base = hypervolume(&refs(&front), &[1.0, 1.0]);
    // 0.8·0.3 + 0.5·0.3 + 0.2·0.3 = 0.45
    assert!((base - 0.45).abs() < 1e-12, "{base}");
    let mut more = front.clone();
    more.push(vec![0.6, 0.5]);
    assert_eq!(hypervolume(&refs(&more), &[1.0, 1.0]), base);
}
