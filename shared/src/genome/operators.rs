//! Variation operators: random initialisation, per-parameter mutation and one-plane crossover
//! (paper §II). All randomness comes from the caller's RNG so a run is reproducible from its seed.

use rand::{Rng, RngExt};
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use super::point::{GaussianPoint, Genome, GenomeLimits};
use crate::material::MaterialId;

/// How children are varied. Defaults follow the paper's Table II (P(mutation) = 0.2).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MutationParams {
    /// Probability that each parameter of each point is mutated (paper: 0.2).
    pub probability: f64,
    /// Standard deviation of a mutation step, as a fraction of the parameter's range. Larger
    /// explores faster, smaller refines better.
    pub step: f64,
    /// Probability that a child gains one new random point.
    pub add_point: f64,
    /// Probability that a child loses one random point.
    pub remove_point: f64,
}

impl Default for MutationParams {
    fn default() -> Self {
        Self {
            probability: 0.2,
            step: 0.05,
            add_point: 0.05,
            remove_point: 0.05,
        }
    }
}

impl MutationParams {
    pub fn validate(&self) -> Result<(), &'static str> {
        let p = |v: f64| (0.0..=1.0).contains(&v);
        if !p(self.probability) {
            return Err("probability");
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err("step");
        }
        if !p(self.add_point) {
            return Err("add_point");
        }
        if !p(self.remove_point) {
            return Err("remove_point");
        }
        Ok(())
    }
}

/// A uniformly random point inside the limits.
pub fn random_point<R: Rng + ?Sized>(
    rng: &mut R,
    limits: &GenomeLimits,
    material_count: usize,
) -> GaussianPoint {
    GaussianPoint {
        position: [rng.random(), rng.random(), rng.random()],
        density: rng.random_range(limits.density[0]..=limits.density[1]),
        falloff: rng.random_range(limits.falloff[0]..=limits.falloff[1]),
        material: MaterialId(rng.random_range(0..material_count) as u8),
    }
}

/// A random genome of `count` points (the paper starts robots from 88).
pub fn random_genome<R: Rng + ?Sized>(
    rng: &mut R,
    count: usize,
    limits: &GenomeLimits,
    material_count: usize,
) -> Genome {
    Genome::new(
        (0..count)
            .map(|_| random_point(rng, limits, material_count))
            .collect(),
    )
}

/// Mutates each parameter with the configured probability (a Gaussian step clamped to its range;
/// a material is redrawn among the others), then occasionally adds or removes a point.
pub fn mutate<R: Rng + ?Sized>(
    genome: &mut Genome,
    rng: &mut R,
    params: &MutationParams,
    limits: &GenomeLimits,
    material_count: usize,
) {
    let step = |rng: &mut R, value: f64, [lo, hi]: [f64; 2]| {
        let z: f64 = StandardNormal.sample(rng);
        (value + z * params.step * (hi - lo)).clamp(lo, hi)
    };
    for p in &mut genome.points {
        for axis in 0..3 {
            if rng.random_bool(params.probability) {
                p.position[axis] = step(rng, p.position[axis], [0.0, 1.0]);
            }
        }
        if rng.random_bool(params.probability) {
            p.density = step(rng, p.density, limits.density);
        }
        if rng.random_bool(params.probability) {
            p.falloff = step(rng, p.falloff, limits.falloff);
        }
        if material_count > 1 && rng.random_bool(params.probability) {
            // Draw among the other materials so a mutation always changes something.
            let other = rng.random_range(0..material_count - 1);
            let other = if other >= p.material.index() {
                other + 1
            } else {
                other
            };
            p.material = MaterialId(other as u8);
        }
    }
    if genome.points.len() < limits.max_points && rng.random_bool(params.add_point) {
        genome
            .points
            .push(random_point(rng, limits, material_count));
    }
    if genome.points.len() > limits.min_points && rng.random_bool(params.remove_point) {
        let i = rng.random_range(0..genome.points.len());
        genome.points.remove(i);
    }
}

/// Moves a genome's continuous parameters (position, density, falloff) by small Gaussian steps,
/// each parameter with probability `probability` and a standard deviation of `step` times its
/// range, clamped to the range. Materials and the number of points stay as they are: this is the
/// refinement move of a local search around a good design, not an exploration move.
pub fn perturb<R: Rng + ?Sized>(
    genome: &mut Genome,
    rng: &mut R,
    probability: f64,
    step: f64,
    limits: &GenomeLimits,
) {
    for p in &mut genome.points {
        nudge_point(p, rng, step, limits, |rng| rng.random_bool(probability));
    }
}

/// Moves every continuous parameter of `count` distinct points drawn at random (all of them when
/// the genome has fewer) by a Gaussian step of `step` times the parameter's range. A nudge that
/// moves one point changes one region of the design, so near a good design it is far likelier to
/// improve it than the same step spread over every point (docs/explanation/search.md measures
/// both).
pub fn perturb_points<R: Rng + ?Sized>(
    genome: &mut Genome,
    rng: &mut R,
    count: usize,
    step: f64,
    limits: &GenomeLimits,
) {
    let n = genome.points.len();
    for i in rand::seq::index::sample(rng, n, count.min(n)) {
        nudge_point(&mut genome.points[i], rng, step, limits, |_| true);
    }
}

/// Nudges each continuous parameter of one point that `chosen` picks (asked once per parameter,
/// in a fixed order, so a seed gives one stream of draws).
fn nudge_point<R: Rng + ?Sized>(
    p: &mut GaussianPoint,
    rng: &mut R,
    step: f64,
    limits: &GenomeLimits,
    mut chosen: impl FnMut(&mut R) -> bool,
) {
    let nudge = |rng: &mut R, value: f64, [lo, hi]: [f64; 2]| {
        let z: f64 = StandardNormal.sample(rng);
        (value + z * step * (hi - lo)).clamp(lo, hi)
    };
    for axis in 0..3 {
        if chosen(rng) {
            p.position[axis] = nudge(rng, p.position[axis], [0.0, 1.0]);
        }
    }
    if chosen(rng) {
        p.density = nudge(rng, p.density, limits.density);
    }
    if chosen(rng) {
        p.falloff = nudge(rng, p.falloff, limits.falloff);
    }
}

/// Which parent gave a crossover child more of its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum DominantParent {
    A,
    B,
}

/// A child of one-plane crossover and the parent it mostly came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossover {
    pub child: Genome,
    pub dominant: DominantParent,
    /// How many of the child's points came from each parent (A, B).
    pub from_parents: (usize, usize),
}

/// A plane through the workspace: a point inside the unit cube and a unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutPlane {
    pub origin: [f64; 3],
    pub normal: [f64; 3],
}

impl CutPlane {
    /// A random plane: origin uniform in the workspace, normal uniform on the sphere.
    pub fn random<R: Rng + ?Sized>(rng: &mut R) -> Self {
        let origin = [rng.random(), rng.random(), rng.random()];
        loop {
            let n: [f64; 3] = [
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
                StandardNormal.sample(rng),
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if len > 1e-9 {
                return Self {
                    origin,
                    normal: [n[0] / len, n[1] / len, n[2] / len],
                };
            }
        }
    }

    /// True on the side the normal points to (points on the plane count as this side).
    pub fn is_front(&self, p: [f64; 3]) -> bool {
        let d: f64 = (0..3)
            .map(|i| (p[i] - self.origin[i]) * self.normal[i])
            .sum();
        d >= 0.0
    }
}

/// One-plane crossover (paper §II): the child takes parent A's points in front of the plane and
/// parent B's points behind it; the parent that gave more points is dominant (A on a tie). The
/// child is cut to `max_points`, keeping A's points first.
pub fn crossover(a: &Genome, b: &Genome, plane: &CutPlane, max_points: usize) -> Crossover {
    let from_a = a.points.iter().filter(|p| plane.is_front(p.position));
    let from_b = b.points.iter().filter(|p| !plane.is_front(p.position));
    let mut points: Vec<GaussianPoint> = from_a.copied().collect();
    let n_a = points.len().min(max_points);
    points.extend(from_b.copied());
    points.truncate(max_points);
    let n_b = points.len() - n_a;
    Crossover {
        child: Genome::new(points),
        dominant: if n_a >= n_b {
            DominantParent::A
        } else {
            DominantParent::B
        },
        from_parents: (n_a, n_b),
    }
}

#[cfg(test)]
mod tests;
