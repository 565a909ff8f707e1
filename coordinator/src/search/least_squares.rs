//! A Gauss-Newton step in the span of an epoch's nudges. The residual model
//! (`search::residual_model`) met its predictions within about 1 % on the circular arc (session
//! 43), yet it only says yes or no to each nudge. A nudge's change of the genome is a direction in
//! parameter space and its residuals less the base's are that direction's measured effect, so the
//! same model can say how far to go along each: the coefficients `c` that minimise
//! `|r + Σ c_k d_k|²` (`r` the design's residuals, `d_k` the directions) give the design
//! `θ + Σ c_k δ_k` (`δ_k` the nudge's parameter changes). A nudge can then be taken further,
//! taken in part, or reversed, and two nudges of one point add up instead of excluding each other.
//!
//! The model is linear only near the design (a voxel flips or not), so every coefficient stays
//! within `reach` of zero. An insertion appends a point: it is taken whole or not at all. The
//! coefficients come from cyclic projected coordinate descent, which converges on this convex
//! box-constrained problem and runs in a fixed order, so a replayed epoch rebuilds the step bit
//! for bit.

use amorph::genome::{GaussianPoint, Genome, GenomeLimits};

use crate::search::residual_model::{Measured, Nudged, changes, squared};

/// A step: each nudge's coefficient (0 for a nudge left out; 0 or 1 for an insertion) and the
/// sum of squares the model predicts for it.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub coefficients: Vec<f64>,
    pub predicted: f64,
}

/// Sweeps of coordinate descent at most; it stops earlier once a sweep moves no coefficient by
/// more than `SETTLED`.
const SWEEPS: usize = 500;
const SETTLED: f64 = 1e-12;

/// The coefficients in `bounds` that minimise `|start + Σ c_k directions_k|²`, from zero. A
/// direction of zero length keeps its coefficient at zero.
pub fn coefficients(start: &[f64], directions: &[Vec<f64>], bounds: &[[f64; 2]]) -> Vec<f64> {
    let mut residual = start.to_vec();
    let mut c = vec![0.0; directions.len()];
    let lengths: Vec<f64> = directions.iter().map(|d| dot(d, d)).collect();
    for _ in 0..SWEEPS {
        let mut moved: f64 = 0.0;
        for (k, d) in directions.iter().enumerate() {
            if lengths[k] == 0.0 {
                continue;
            }
            let [lo, hi] = bounds[k];
            let next = (c[k] - dot(d, &residual) / lengths[k]).clamp(lo, hi);
            let change = next - c[k];
            if change != 0.0 {
                for (r, x) in residual.iter_mut().zip(d) {
                    *r += change * x;
                }
                c[k] = next;
                moved = moved.max(change.abs());
            }
        }
        if moved <= SETTLED {
            break;
        }
    }
    c
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// What a nudge changed of `base`: whether it appended points (an insertion, taken whole), or
/// `None` when it has fewer points or changes nothing.
fn appends(base: &Genome, nudge: &Genome) -> Option<bool> {
    let (moved, appended) = changes(base, nudge)?;
    (!moved.is_empty() || !appended.is_empty()).then_some(!appended.is_empty())
}

/// The model's step from `onto` (`base`, or a design that descends from it) along the nudges
/// (all bred from `base`), each coefficient within `reach` of zero, an insertion whole or not at
/// all (and not one whose points `onto` already appended, nor past `max_points`). `None` when no
/// step lowers `onto`'s predicted sum of squares.
pub fn step(
    base: &Measured,
    onto: &Measured,
    nudges: &[Nudged],
    reach: f64,
    max_points: usize,
) -> Option<Step> {
    let n = base.genome.points.len();
    let stations = base.residuals.len();
    if onto.genome.points.len() < n || onto.residuals.len() != stations {
        return None;
    }
    let onto_appended = &onto.genome.points[n..];
    let mut bounds = Vec::with_capacity(nudges.len());
    let mut insertion = Vec::with_capacity(nudges.len());
    let directions: Vec<Vec<f64>> = (nudges.iter())
        .map(|nudge| {
            let kind = appends(base.genome, nudge.genome)
                .filter(|_| nudge.residuals.len() == stations)
                .filter(|_| {
                    !nudge.genome.points[n..]
                        .iter()
                        .any(|p| onto_appended.contains(p))
                });
            insertion.push(kind == Some(true));
            bounds.push(match kind {
                None => [0.0, 0.0],
                Some(true) => [0.0, 1.0],
                Some(false) => [-reach, reach],
            });
            match kind {
                None => vec![0.0; stations],
                Some(_) => (nudge.residuals.iter().zip(base.residuals))
                    .map(|(r, b)| r - b)
                    .collect(),
            }
        })
        .collect();
    let relaxed = coefficients(onto.residuals, &directions, &bounds);
    // Insertions the relaxed problem takes more than half of are taken whole, most wanted first
    // (the lower index on a tie) while they fit; the others are left out, and the moves are
    // solved again around them.
    let mut wanted: Vec<usize> = (0..nudges.len())
        .filter(|&k| insertion[k] && relaxed[k] >= 0.5)
        .collect();
    wanted.sort_by(|&a, &b| relaxed[b].total_cmp(&relaxed[a]));
    let mut start = onto.residuals.to_vec();
    let mut points = onto.genome.points.len();
    let mut whole = vec![false; nudges.len()];
    for k in wanted {
        let extra = nudges[k].genome.points.len() - n;
        if points + extra <= max_points {
            points += extra;
            whole[k] = true;
            for (s, d) in start.iter_mut().zip(&directions[k]) {
                *s += d;
            }
        }
    }
    for (k, b) in bounds.iter_mut().enumerate() {
        if insertion[k] {
            *b = [0.0, 0.0];
        }
    }
    let mut c = coefficients(&start, &directions, &bounds);
    for (k, c) in c.iter_mut().enumerate() {
        if whole[k] {
            *c = 1.0;
        }
    }
    let mut predicted = onto.residuals.to_vec();
    for (d, &c) in directions.iter().zip(&c) {
        for (p, x) in predicted.iter_mut().zip(d) {
            *p += c * x;
        }
    }
    let predicted = squared(predicted.into_iter());
    let onto_error = squared(onto.residuals.iter().copied());
    (predicted < onto_error).then_some(Step {
        coefficients: c,
        predicted,
    })
}

/// `onto` with `scale` times the step applied: each point of `base` moved by the coefficients
/// times its nudges' changes (a move's coefficient scaled, an insertion's not), clamped to the
/// parameters' ranges, and the points of the insertions taken appended. `None` when that is
/// `onto` itself.
pub fn apply(
    base: &Genome,
    onto: &Genome,
    nudges: &[Nudged],
    step: &Step,
    scale: f64,
    limits: &GenomeLimits,
) -> Option<Genome> {
    let n = base.points.len();
    let mut design = onto.clone();
    for (nudge, &c) in nudges.iter().zip(&step.coefficients) {
        if c == 0.0 {
            continue;
        }
        let whole = nudge.genome.points.len() > n;
        let c = if whole { c } else { c * scale };
        for (i, (moved, from)) in nudge.genome.points.iter().zip(&base.points).enumerate() {
            if moved != from {
                shift(&mut design.points[i], moved, from, c);
            }
        }
        if whole {
            design.points.extend_from_slice(&nudge.genome.points[n..]);
        }
    }
    for p in &mut design.points[..n] {
        clamp(p, limits);
    }
    (design != *onto).then_some(design)
}

/// Adds `c` times (`moved` less `from`) to each continuous parameter of `p`.
fn shift(p: &mut GaussianPoint, moved: &GaussianPoint, from: &GaussianPoint, c: f64) {
    for axis in 0..3 {
        p.position[axis] += c * (moved.position[axis] - from.position[axis]);
    }
    p.density += c * (moved.density - from.density);
    p.falloff += c * (moved.falloff - from.falloff);
}

fn clamp(p: &mut GaussianPoint, limits: &GenomeLimits) {
    for x in &mut p.position {
        *x = x.clamp(0.0, 1.0);
    }
    p.density = p.density.clamp(limits.density[0], limits.density[1]);
    p.falloff = p.falloff.clamp(limits.falloff[0], limits.falloff[1]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::fixtures::{moved, points_at as genome};

    /// Two non-orthogonal directions spanning the plane: the unconstrained minimum solves the
    /// normal equations exactly (here r + 1·d0 − 2·d1 = 0).
    #[test]
    fn unbounded_coefficients_solve_the_normal_equations() {
        let d = vec![vec![1.0, 1.0], vec![0.0, 1.0]];
        let r = [-1.0, 1.0];
        let c = coefficients(&r, &d, &[[-10.0, 10.0]; 2]);
        assert!(
            (c[0] - 1.0).abs() < 1e-9 && (c[1] + 2.0).abs() < 1e-9,
            "{c:?}"
        );
    }

    /// With a bound on the coefficient that would reach the minimum, the other coefficient makes
    /// up what it can (the box-constrained minimum, worked by hand), and a direction of zero
    /// length keeps its coefficient at zero.
    #[test]
    fn bounded_coefficients_take_the_constrained_minimum() {
        let d = vec![vec![1.0, 1.0], vec![0.0, 1.0], vec![0.0, 0.0]];
        let r = [-1.0, 1.0];
        let c = coefficients(&r, &d, &[[-10.0, 10.0], [-1.0, 1.0], [-1.0, 1.0]]);
        // c1 = -1 at its bound; then c0 minimises (c0 - 1)² + c0² → c0 = 0.5.
        assert!(
            (c[0] - 0.5).abs() < 1e-9 && c[1] == -1.0 && c[2] == 0.0,
            "{c:?}"
        );
    }

    /// A nudge that made the design exactly worse is reversed, a nudge that fixed half of the
    /// error is taken twice over, within the reach; a reach of one stops it at the whole nudge.
    #[test]
    fn a_nudge_is_reversed_or_taken_further() {
        let base = genome(&[0.1, 0.2, 0.3]);
        let (worse, half) = (moved(&base, 0, 0.01), moved(&base, 1, 0.01));
        let r0 = [1.0, 1.0];
        let nudges = [
            Nudged {
                genome: &worse,
                residuals: vec![2.0, 1.0],
            },
            Nudged {
                genome: &half,
                residuals: vec![1.0, 0.5],
            },
        ];
        let base_m = Measured {
            genome: &base,
            residuals: &r0,
        };
        let step = super::step(&base_m, &base_m, &nudges, 2.0, 10).expect("a step");
        assert!(
            (step.coefficients[0] + 1.0).abs() < 1e-9 && (step.coefficients[1] - 2.0).abs() < 1e-9,
            "{:?}",
            step.coefficients
        );
        assert!(step.predicted < 1e-18);
        let design = apply(&base, &base, &nudges, &step, 1.0, &GenomeLimits::default())
            .expect("a new design");
        assert!((design.points[0].position[0] - 0.09).abs() < 1e-12);
        assert!((design.points[1].position[0] - 0.22).abs() < 1e-12);
        assert_eq!(design.points[2], base.points[2]);
        let short = super::step(&base_m, &base_m, &nudges, 1.0, 10).expect("a step");
        assert_eq!(short.coefficients[1], 1.0);
    }

    /// Two nudges of one point add up in parameter space, a half step halves the moves but not
    /// an insertion (taken whole), and the design stays in the parameters' ranges.
    #[test]
    fn moves_add_up_scale_and_clamp_while_insertions_stay_whole() {
        let base = genome(&[0.1, 0.98]);
        let a = moved(&base, 0, 0.02);
        let mut b = moved(&base, 0, 0.01);
        b.points[0].density += 0.2;
        let far = moved(&base, 1, 0.02);
        let inserted = genome(&[0.1, 0.98, 0.6]);
        let nudges: Vec<Nudged> = [&a, &b, &far, &inserted]
            .into_iter()
            .map(|genome| Nudged {
                genome,
                residuals: vec![0.0],
            })
            .collect();
        let step = Step {
            coefficients: vec![1.0, 2.0, 3.0, 1.0],
            predicted: 0.0,
        };
        let limits = GenomeLimits::default();
        let whole = apply(&base, &base, &nudges, &step, 1.0, &limits).expect("a design");
        assert!((whole.points[0].position[0] - 0.14).abs() < 1e-12);
        assert!((whole.points[0].density - 0.9).abs() < 1e-12);
        assert_eq!(whole.points[1].position[0], 1.0, "clamped to the workspace");
        assert_eq!(whole.points[2], inserted.points[2]);
        let half = apply(&base, &base, &nudges, &step, 0.5, &limits).expect("a design");
        assert!((half.points[0].position[0] - 0.12).abs() < 1e-12);
        assert!((half.points[0].density - 0.7).abs() < 1e-12);
        assert_eq!(half.points.len(), 3, "the insertion is not halved");
    }

    /// An insertion is taken whole when the relaxed problem wants more than half of it, not
    /// when `onto` already holds its point or the point limit is reached; no step when nothing
    /// lowers the error.
    #[test]
    fn insertions_are_whole_or_out() {
        let base = genome(&[0.1]);
        let inserted = genome(&[0.1, 0.7]);
        let useless = moved(&base, 0, 0.01);
        let nudges = [
            Nudged {
                genome: &inserted,
                residuals: vec![0.2],
            },
            Nudged {
                genome: &useless,
                residuals: vec![1.0],
            },
        ];
        let r0 = [1.0];
        let base_m = Measured {
            genome: &base,
            residuals: &r0,
        };
        let step = super::step(&base_m, &base_m, &nudges, 1.0, 10).expect("a step");
        assert_eq!(step.coefficients, vec![1.0, 0.0]);
        assert!((step.predicted - 0.04).abs() < 1e-12);
        assert_eq!(super::step(&base_m, &base_m, &nudges, 1.0, 1), None);
        let onto_r = [0.2];
        let onto = Measured {
            genome: &inserted,
            residuals: &onto_r,
        };
        assert_eq!(super::step(&base_m, &onto, &nudges, 1.0, 10), None);
    }
}
