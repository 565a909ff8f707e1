//! What a child is, read back from its genome alone: a copy of a base design (the run's best it
//! was bred from), one of its points moved, one point appended, several such changes at once (a
//! combination of nudges), or something else (a crossover child, a mutation of another parent).
//!
//! A stored run records genomes, not the operators that made them, and the order in which an
//! epoch's children are stored depends on settings (islands, shared climb, `finest_fraction`). The
//! local search's moves have a fixed shape against their base: a nudge changes points in place and
//! an insertion appends, so reading the shape names the move whatever the settings were. That is
//! how the climb's sources are counted from stores (`climb_sources` bench, docs/evolution.md).

use amorph::genome::Genome;

/// How a child's genome relates to a base genome.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StepKind {
    /// The base's points, unchanged.
    Copy,
    /// One point's continuous parameters changed, its material kept: a one-point nudge.
    Move,
    /// The base's points unchanged, one point appended: a boundary insertion.
    Insertion,
    /// Several points changed in place (materials kept) and/or appended, no more than half of
    /// the base's points changed: nudges added up.
    Combined,
    /// None of these: points removed, a material changed, or most of the design changed.
    Other,
}

impl StepKind {
    pub const ALL: [StepKind; 5] = [
        StepKind::Copy,
        StepKind::Move,
        StepKind::Insertion,
        StepKind::Combined,
        StepKind::Other,
    ];

    /// A short lower-case name for tables.
    pub fn name(self) -> &'static str {
        match self {
            StepKind::Copy => "copy",
            StepKind::Move => "move",
            StepKind::Insertion => "insertion",
            StepKind::Combined => "combined",
            StepKind::Other => "other",
        }
    }
}

/// The kind of step that takes `base` to `child`, by position: point `i` of the child is point
/// `i` of the base, changed or not, and the child's points past the base's length are appended.
pub fn step_kind(base: &Genome, child: &Genome) -> StepKind {
    let (b, c) = (&base.points, &child.points);
    if c.len() < b.len() {
        return StepKind::Other;
    }
    let mut moved = 0;
    for (p, q) in b.iter().zip(c) {
        if p != q {
            if p.material != q.material {
                return StepKind::Other;
            }
            moved += 1;
        }
    }
    let appended = c.len() - b.len();
    match (moved, appended) {
        (0, 0) => StepKind::Copy,
        (1, 0) => StepKind::Move,
        (0, 1) => StepKind::Insertion,
        _ if 2 * moved <= b.len() => StepKind::Combined,
        _ => StepKind::Other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amorph::genome::{GenomeLimits, perturb_points, random_genome};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn base(seed: u64) -> (Genome, GenomeLimits, ChaCha8Rng) {
        let limits = GenomeLimits::default();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let genome = random_genome(&mut rng, 40, &limits, 2);
        (genome, limits, rng)
    }

    /// The local search's own operator, one point at a time, is read back as a move on every
    /// draw, and two draws on the same copy as a combination (or a move where both hit one point).
    #[test]
    fn one_point_nudges_read_as_moves_and_two_as_combined() {
        for seed in 0..50 {
            let (genome, limits, mut rng) = base(seed);
            let mut child = genome.clone();
            perturb_points(&mut child, &mut rng, 1, 0.02, &limits);
            assert_eq!(step_kind(&genome, &child), StepKind::Move, "seed {seed}");
            perturb_points(&mut child, &mut rng, 1, 0.02, &limits);
            let kind = step_kind(&genome, &child);
            assert!(
                matches!(kind, StepKind::Combined | StepKind::Move),
                "seed {seed}: {kind:?}"
            );
        }
    }

    #[test]
    fn an_appended_point_is_an_insertion_and_a_copy_is_a_copy() {
        let (genome, _, _) = base(1);
        assert_eq!(step_kind(&genome, &genome), StepKind::Copy);
        let mut child = genome.clone();
        child.points.push(genome.points[3]);
        assert_eq!(step_kind(&genome, &child), StepKind::Insertion);
        child.points.push(genome.points[4]);
        assert_eq!(step_kind(&genome, &child), StepKind::Combined);
    }

    /// The shared climb's own step (`LocalSearchParams::step_from_best`, half insertions at the
    /// design's boundary) reads back as exactly what it did: an appended point or one point moved.
    #[test]
    fn the_local_searchs_steps_read_back_as_insertions_or_moves() {
        let scene: amorph::task::Scene =
            toml::from_str("kind = \"beam\"\ntarget = \"circular_arc\"").expect("a beam");
        let dims = amorph::voxel::GridDims::new(6, 20, 6);
        let local = crate::search::LocalSearchParams {
            fraction: 1.0,
            insertion: 0.5,
            ..Default::default()
        };
        let (genome, _, mut rng) = base(3);
        let site = crate::search::BoundarySite::new(&genome, &scene, dims);
        let mut seen = std::collections::BTreeMap::new();
        for _ in 0..200 {
            let mut child = genome.clone();
            local.step_from_best(&mut child, &mut rng, Some(&site), &scene);
            let kind = step_kind(&genome, &child);
            let expected = if child.points.len() > genome.points.len() {
                StepKind::Insertion
            } else {
                StepKind::Move
            };
            assert_eq!(kind, expected);
            *seen.entry(kind).or_insert(0) += 1;
        }
        assert_eq!(seen.len(), 2, "both kinds drawn: {seen:?}");
    }

    /// A removed point or a changed material is never a climb step, and neither is an unrelated
    /// design (every point differs). A crossover child that keeps every base point in place and
    /// appends the other parent's reads as a climb step: the shape is what is counted.
    #[test]
    fn removals_material_changes_and_strangers_are_other() {
        let (genome, limits, mut rng) = base(2);
        let mut shorter = genome.clone();
        shorter.points.pop();
        assert_eq!(step_kind(&genome, &shorter), StepKind::Other);
        let mut recoloured = genome.clone();
        let m = &mut recoloured.points[0].material;
        m.0 = 1 - m.0.min(1);
        assert_eq!(step_kind(&genome, &recoloured), StepKind::Other);
        let stranger = random_genome(&mut rng, 40, &limits, 2);
        assert_eq!(step_kind(&genome, &stranger), StepKind::Other);
        let mut half = genome.clone();
        for p in half.points.iter_mut().take(21) {
            p.density = -p.density;
        }
        assert_eq!(step_kind(&genome, &half), StepKind::Other);
        half.points[20] = genome.points[20];
        assert_eq!(step_kind(&genome, &half), StepKind::Combined);
    }
}
