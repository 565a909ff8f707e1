//! The stiffness task: its fitness against beam theory, its ranking of layouts of the same hard
//! budget, its feasibility rule, and its check of outcomes claimed by peers.

use amorph::material::MaterialId;
use amorph::task::stiffness::{StiffnessMetrics, StiffnessScene, simulate_stiffness};
use amorph::task::{Metrics, Outcome, Scene};
use amorph::voxel::{GridDims, VoxelGrid};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const HARD: Option<MaterialId> = Some(MaterialId(0));
const SOFT: Option<MaterialId> = Some(MaterialId(1));

fn layout(dims: GridDims, hard: impl Fn(usize, usize, usize) -> bool) -> VoxelGrid {
    let mut grid = VoxelGrid::empty(dims);
    for z in 0..dims.nz {
        for y in 0..dims.ny {
            for x in 0..dims.nx {
                grid.set(x, y, z, if hard(x, y, z) { HARD } else { SOFT });
            }
        }
    }
    grid
}

fn metrics(grid: &VoxelGrid, scene: &StiffnessScene) -> (f64, StiffnessMetrics) {
    match simulate_stiffness(grid, scene) {
        amorph::outcome::Outcome::Evaluated { fitness, metrics } => (fitness, metrics),
        failed => panic!("{failed:?}"),
    }
}

#[test]
fn a_slender_all_hard_beam_has_the_stiffness_beam_theory_gives() {
    // The fitness's scale is the Euler–Bernoulli deflection P L³ / 3EI of the all-hard workspace.
    // At a slenderness of 20 Timoshenko's shear term adds 3EI/(κGAL²) = (E/G)(h/L)²/(4κ) ≈ 0.2 %
    // (E/G = 2.7, κ = 5/6), so the voxel model must give 1 within 2 %.
    let scene = StiffnessScene {
        max_hard_fraction: 1.0,
        ..StiffnessScene::default()
    };
    let dims = GridDims::new(2, 40, 2);
    let (_, m) = metrics(&layout(dims, |_, _, _| true), &scene);
    eprintln!("relative stiffness {}", m.relative_stiffness);
    assert!(
        (m.relative_stiffness - 1.0).abs() < 0.02,
        "{}",
        m.relative_stiffness
    );
    assert!(m.within_budget);
}

#[test]
fn flanges_beat_a_top_slab_and_a_random_layout_of_the_same_budget() {
    let scene = StiffnessScene::default(); // 30 % hard
    let dims = GridDims::new(10, 30, 10);
    // 30 of each layer's 100 cells hard: the top three rows; an I-beam (top and bottom rows, a
    // one-voxel web between them, one spare cell at each flange's root); or 30 % at random.
    let slab = layout(dims, |_, _, z| z >= 7);
    let flanges = layout(dims, |x, _, z| {
        z == 0 || z == 9 || x == 4 || (x == 5 && (z == 1 || z == 8))
    });
    // Exactly 30 % of the cells, drawn without replacement: a layout at the budget, never over.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut picks = vec![false; dims.cell_count()];
    for i in rand::seq::index::sample(&mut rng, dims.cell_count(), dims.cell_count() * 3 / 10) {
        picks[i] = true;
    }
    let random = layout(dims, |x, y, z| picks[dims.index(x, y, z)]);
    let (f_slab, m_slab) = metrics(&slab, &scene);
    let (f_flanges, m_flanges) = metrics(&flanges, &scene);
    let (f_random, m_random) = metrics(&random, &scene);
    eprintln!(
        "slab {f_slab} ({}), flanges {f_flanges} ({}), random {f_random} ({}, {:.3} hard)",
        m_slab.flange_efficiency,
        m_flanges.flange_efficiency,
        m_random.flange_efficiency,
        m_random.hard_fraction
    );
    assert_eq!(m_slab.hard_fraction, 0.3);
    assert_eq!(m_flanges.hard_fraction, 0.3);
    assert_eq!(m_random.hard_fraction, 0.3);
    assert!(m_slab.within_budget && m_flanges.within_budget && m_random.within_budget);
    // Beam theory (unit cells): the I-beam's hard second moment about its centroid is
    // 2·10·4.5² + 2·(3.5² + 2.5² + 1.5² + 0.5²) + 2·3.5² + 30/12 ≈ 474, the slab's 10·3³/12 = 22.5;
    // the hard web carries the shear, whose deflection adds about half the bending one here
    // (P/(G A_web) against P l³/(3EI)), so the I-beam is ~13× stiffer: 2× is a safe floor.
    // Random hard voxels float in soft material and carry little.
    assert!(f_flanges > 2.0 * f_slab, "{f_flanges} vs {f_slab}");
    assert!(f_flanges > 2.0 * f_random, "{f_flanges} vs {f_random}");
    assert!(m_flanges.flange_efficiency > 0.85 && m_flanges.flange_efficiency <= 1.0);
    assert!(m_slab.flange_efficiency < 0.1);
}

#[test]
fn every_design_within_the_budget_ranks_above_every_design_over_it() {
    let scene = StiffnessScene::default();
    let dims = GridDims::new(4, 12, 4);
    // All hard (100 %, far over) against all soft (0 %, within): stiffness loses to feasibility.
    let (f_hard, m_hard) = metrics(&layout(dims, |_, _, _| true), &scene);
    let (f_soft, m_soft) = metrics(&layout(dims, |_, _, _| false), &scene);
    assert!(!m_hard.within_budget && m_soft.within_budget);
    assert!(m_hard.relative_stiffness > 100.0 * m_soft.relative_stiffness);
    assert!(f_soft > 0.0 && f_hard < 0.0 && f_soft > f_hard);
    // Over the budget, the smaller excess wins.
    let (f_half, _) = metrics(&layout(dims, |_, _, z| z >= 2), &scene);
    assert!(f_half > f_hard, "{f_half} vs {f_hard}");
    assert_eq!(f_half, 0.3 - 0.5);
}

#[test]
fn an_outcome_whose_numbers_disagree_with_its_counts_is_refused() {
    let scene = Scene::Stiffness(StiffnessScene::default());
    let dims = GridDims::new(4, 12, 4);
    let Scene::Stiffness(inner) = &scene else {
        unreachable!()
    };
    let (fitness, m) = metrics(&layout(dims, |_, _, z| z == 0 || z == 3), inner);
    let honest = Outcome::Evaluated {
        fitness,
        metrics: Metrics::Stiffness(m.clone()),
    };
    assert_eq!(scene.check_outcome(&honest, dims), Ok(()));
    let forged = [
        Outcome::Evaluated {
            fitness: fitness * 2.0,
            metrics: Metrics::Stiffness(m.clone()),
        },
        Outcome::Evaluated {
            fitness,
            metrics: Metrics::Stiffness(StiffnessMetrics {
                relative_stiffness: 9.0,
                ..m.clone()
            }),
        },
        Outcome::Evaluated {
            fitness,
            metrics: Metrics::Stiffness(StiffnessMetrics {
                voxels: 10_000,
                ..m.clone()
            }),
        },
    ];
    for outcome in forged {
        assert!(
            scene.check_outcome(&outcome, dims).is_err(),
            "{outcome:?} accepted"
        );
    }
}
