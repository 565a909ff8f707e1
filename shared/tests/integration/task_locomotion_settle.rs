//! The damped settle: the settling damping is on only while settling; a light one brings a
//! swaying body to the same rest height sooner, a heavy one overdamps it into a creep; unset, the
//! protocol is the paper's.

use amorph::dynamics::{DynamicScene, Pass, foam_palette};
use amorph::material::MaterialId;
use amorph::task::locomotion::{
    LocomotionPhase, LocomotionProtocol, SettleRule, simulate_locomotion_observed,
};
use amorph::voxel::{GridDims, VoxelGrid};

/// A 3×3×2 foot of passive foam (1 mm voxels) with a 9 mm arm, 3 wide and 1 thick, held out one
/// voxel above the floor: under gravity the arm sags (~0.2 mm at its tip) and then sways at its
/// first bending frequency (ω₁ = 3.52 √(EI/(ρAL⁴)) ≈ 300 rad/s), which link damping, made for the
/// lattice's top mode, leaves almost undamped.
fn arm() -> VoxelGrid {
    let mut grid = VoxelGrid::empty(GridDims::new(12, 3, 2));
    for x in 0..12 {
        for y in 0..3 {
            for z in 0..2 {
                if x < 3 || z == 1 {
                    grid.set(x, y, z, Some(MaterialId(0)));
                }
            }
        }
    }
    grid
}

fn protocol(damping: Option<f64>) -> LocomotionProtocol {
    LocomotionProtocol {
        actuation_cycles: 1,
        settle: SettleRule {
            damping,
            // Long enough for the undamped sway to die out too, so both end still.
            max_time: 8.0,
            ..SettleRule::default()
        },
        ..LocomotionProtocol::default()
    }
}

#[test]
fn the_settling_damping_is_on_while_settling_and_off_for_the_gait() {
    let scene = DynamicScene::paper_locomotion();
    assert_eq!(scene.damping.global, 0.0);
    let mut seen = Vec::new();
    simulate_locomotion_observed(
        &arm(),
        &foam_palette(),
        &scene,
        &protocol(Some(0.1)),
        4,
        &mut |phase, sim| {
            seen.push((
                matches!(phase, LocomotionPhase::Settling),
                sim.passes().contains(&Pass::GlobalDamping),
            ))
        },
    );
    assert!(seen.iter().any(|&(settling, _)| settling));
    assert!(seen.iter().any(|&(settling, _)| !settling));
    for (settling, damped) in seen {
        assert_eq!(
            settling, damped,
            "global damping must be on exactly while settling"
        );
    }
}

#[test]
fn a_light_settling_damping_settles_sooner_and_a_heavy_one_creeps() {
    let scene = DynamicScene::paper_locomotion();
    let settle = |damping: Option<f64>| {
        let mut rest = None;
        let outcome = simulate_locomotion_observed(
            &arm(),
            &foam_palette(),
            &scene,
            &protocol(damping),
            4,
            &mut |phase, sim| {
                if matches!(phase, LocomotionPhase::Settled) {
                    rest = Some(sim.centre_of_mass());
                }
            },
        );
        (outcome.settle_time, rest.unwrap())
    };
    let (own_time, own_rest) = settle(None);
    assert!(own_time < 8.0, "the arm never came to rest");
    // The arm sways at ω₁ ≈ 300 rad/s, ω_voxel/ω₁ ≈ 80: ζ = 0.003 gives that sway about a
    // quarter of critical damping and must shorten the settle; ζ = 0.1 gives it eight times
    // critical, an overdamped creep that must lengthen it.
    let (light_time, light_rest) = settle(Some(0.003));
    let (heavy_time, heavy_rest) = settle(Some(0.1));
    assert!(
        light_time < own_time && own_time < heavy_time,
        "settled after {light_time} s (ζ = 0.003), {own_time} s (own), {heavy_time} s (ζ = 0.1)"
    );
    // All three are the arm at rest under gravity. Vertically that rest is unique: a body slower
    // than `still_speed` (1 mm/s) swinging at ω ≈ 300 rad/s is within v/ω ≈ 3 µm of it, so two
    // heights agree within twice that. Along the floor they need not: with Coulomb friction a
    // body comes to rest wherever its landing slid it. Across the arm (y) the body is symmetric,
    // and so must every rest be.
    for rest in [light_rest, heavy_rest] {
        let gap = (rest.z - own_rest.z).abs();
        assert!(gap < 6e-6, "rest heights differ by {gap} m");
        assert!((rest.y - own_rest.y).abs() < 1e-12);
    }
}

#[test]
fn without_a_settling_damping_the_protocol_is_the_papers() {
    // `settle.damping` unset must leave the evaluation bit for bit as before the key existed:
    // the same as setting it to the scene's own value, which adds no pass.
    let scene = DynamicScene::paper_locomotion();
    let run = |damping| {
        amorph::task::locomotion::simulate_locomotion(
            &arm(),
            &foam_palette(),
            &scene,
            &protocol(damping),
        )
    };
    assert_eq!(run(None), run(Some(scene.damping.global)));
}
