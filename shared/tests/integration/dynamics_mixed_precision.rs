//! The mixed-precision link kernel over a whole locomotion evaluation: it moves a walking robot's
//! gait less than halving the time step does. That is the yardstick of docs/explanation/physics.md:
//! a gait is a chaotic contact problem, so a change of fitness means something only against what a
//! finer step changes.

use amorph::dynamics::{DynamicScene, LinkPrecision, foam_palette};
use amorph::genome::{GenomeLimits, random_genome};
use amorph::task::locomotion::{LocomotionProtocol, LocomotionStatus, simulate_locomotion};
use amorph::voxel::{DEFAULT_THRESHOLD, GridDims, keep_largest_component, voxelize};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The settling study's random robot 13 at 10³ (2 mm voxels, 358 voxels): of its twenty, the one
/// that really walks (~10 mm in ten cycles), so its gait is not noise around zero.
#[test]
fn the_mixed_kernel_moves_a_walker_less_than_half_the_time_step_does() {
    let n = 10;
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let genome = random_genome(&mut rng, 88, &GenomeLimits::default(), 2);
    let grid = keep_largest_component(&voxelize(
        &genome,
        GridDims::new(n, n, n),
        2,
        DEFAULT_THRESHOLD,
    ));
    let evaluate = |link_precision: LinkPrecision, dt_fraction: f64| {
        let scene = DynamicScene {
            voxel_size: 0.02 / n as f64,
            dt_fraction,
            link_precision,
            ..DynamicScene::paper_locomotion()
        };
        let outcome = simulate_locomotion(
            &grid,
            &foam_palette(),
            &scene,
            &LocomotionProtocol::default(),
        );
        assert_eq!(
            outcome.status,
            LocomotionStatus::Completed,
            "{link_precision:?}, dt x{dt_fraction}"
        );
        outcome.fitness
    };
    // Side by side: each is a whole evaluation, the half step two.
    let (double, mixed, half_step) = std::thread::scope(|s| {
        let double = s.spawn(|| evaluate(LinkPrecision::Double, 1.0));
        let mixed = s.spawn(|| evaluate(LinkPrecision::Mixed, 1.0));
        let half_step = evaluate(LinkPrecision::Double, 0.5);
        (double.join().unwrap(), mixed.join().unwrap(), half_step)
    });
    eprintln!(
        "gait: double {:.6} mm, mixed {:.6} mm, half step {:.6} mm",
        double * 1e3,
        mixed * 1e3,
        half_step * 1e3
    );
    assert!(double > 5e-3, "the robot walks: {double} m");
    assert_ne!(mixed.to_bits(), double.to_bits(), "the mixed kernel ran");
    assert!(
        (mixed - double).abs() < (half_step - double).abs(),
        "mixed {mixed} against double {double}, half step {half_step}"
    );
}

/// The mixed kernel reads an `f32` copy of the state that the integration writes; a velocity set
/// between steps must reach it. Two voxels at rest in free space, one step, then voxel 1 is
/// given 1 mm/s along the link: the link's damping pushes voxel 0 along in the next step. A
/// copy left stale would see them at rest and push nothing.
#[test]
fn a_velocity_set_between_steps_reaches_the_mixed_kernel() {
    use amorph::dynamics::{Simulation, Vec3};
    use amorph::material::{Material, MaterialId, Palette};
    use amorph::voxel::VoxelGrid;
    let grid = VoxelGrid::filled(GridDims::new(2, 1, 1), MaterialId(0));
    let palette = Palette(vec![Material::new("m", 1.0e6, 0.35)]);
    let kick = |link_precision: LinkPrecision| {
        let scene = DynamicScene {
            link_precision,
            damping: amorph::dynamics::DampingParams {
                link: 1.0,
                global: 0.0,
                contact: 0.0,
            },
            ..DynamicScene::free_space(0.01)
        };
        let mut sim = Simulation::new(&grid, &palette, &scene).unwrap();
        sim.step().unwrap();
        sim.set_velocity(1, Vec3::new(1e-3, 0.0, 0.0)).unwrap();
        sim.step().unwrap();
        sim.velocities()[0].x
    };
    let (double, mixed) = (kick(LinkPrecision::Double), kick(LinkPrecision::Mixed));
    assert!(double > 0.0, "the damping pulls voxel 0 along: {double}");
    // f32 rounding of the velocities and the damping time: a few parts in 1e7.
    assert!(
        (mixed - double).abs() <= 1e-5 * double,
        "mixed {mixed}, double {double}"
    );
}
