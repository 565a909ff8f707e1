//! Locomotion along a heading and up an incline: the fitness is travel along the heading, the
//! slope rises along it, and turning the robot with its heading changes nothing.

use amorph::material::MaterialId;
use amorph::task::locomotion::{LocomotionMetrics, LocomotionScene};
use amorph::task::{Task, TaskOutcome};
use amorph::voxel::{GridDims, VoxelGrid};

/// A short protocol on a small workspace: settle 0.02 s, two 0.02 s cycles.
fn scene(heading_degrees: f64, incline_degrees: f64) -> LocomotionScene {
    let mut scene = LocomotionScene {
        workspace: 0.006,
        heading_degrees,
        incline_degrees,
        actuation_cycles: 2,
        ..LocomotionScene::default()
    };
    scene.settle.max_time = 0.02;
    if let Some(a) = scene.dynamics.actuation.as_mut() {
        a.period = 0.02;
    }
    scene
}

fn walk(scene: &LocomotionScene, body: &VoxelGrid) -> LocomotionMetrics {
    scene.validate().unwrap();
    match scene.simulate(body) {
        TaskOutcome::Evaluated { metrics, .. } => metrics,
        failed => panic!("{failed:?}"),
    }
}

/// An asymmetric robot (an actuated foot at one end of a passive slab), so it walks one way.
fn robot() -> VoxelGrid {
    let dims = GridDims::new(6, 4, 3);
    let mut grid = VoxelGrid::empty(dims);
    for x in 0..6 {
        for y in 0..4 {
            grid.set(x, y, 0, Some(MaterialId(u8::from(x < 2))));
            if x >= 3 {
                grid.set(x, y, 1, Some(MaterialId(0)));
            }
        }
    }
    grid.set(5, 0, 2, Some(MaterialId(0)));
    grid
}

/// The same robot turned +90° about Z: cell (x, y) goes to (ny − 1 − y, x).
fn turned(grid: &VoxelGrid) -> VoxelGrid {
    let d = grid.dims();
    let mut out = VoxelGrid::empty(GridDims::new(d.ny, d.nx, d.nz));
    for z in 0..d.nz {
        for y in 0..d.ny {
            for x in 0..d.nx {
                out.set(d.ny - 1 - y, x, z, grid.get(x, y, z));
            }
        }
    }
    out
}

#[test]
fn a_robot_turned_with_its_heading_walks_the_same() {
    // Turning robot and heading together is a symmetry of the physics (floor, gravity and
    // friction are isotropic in the plane). The two runs differ only in floating-point order,
    // so any error in the heading (a sign, a swapped sine) would show as an O(1) difference;
    // 1e-3 of the travel leaves room for rounding amplified over the run.
    let body = robot();
    let plain = walk(&scene(0.0, 0.0), &body);
    let turned = walk(&scene(90.0, 0.0), &turned(&body));
    eprintln!(
        "travel {} vs {}, lateral {} vs {}",
        plain.displacement, turned.displacement, plain.lateral, turned.lateral
    );
    // At rest the centre of mass would jitter by far less than a micrometre.
    assert!(
        plain.displacement.abs() > 1e-6,
        "the robot should move: {}",
        plain.displacement
    );
    let tol = 1e-3 * plain.displacement.abs();
    assert!((plain.displacement - turned.displacement).abs() < tol);
    assert!((plain.gait_displacement - turned.gait_displacement).abs() < tol);
    assert!((plain.lateral - turned.lateral).abs() < tol.max(1e-9));
    assert!((plain.body_length - turned.body_length).abs() < 1e-12);
}

#[test]
fn a_steep_slope_rising_along_the_heading_slides_the_robot_back() {
    // 50° exceeds the foams' static friction angle (atan 1.0 = 45°), so the body slides
    // downhill, against the heading, whichever way the heading points, and straight down it.
    let body = robot();
    for heading in [0.0, 90.0, 210.0] {
        let m = walk(&scene(heading, 50.0), &body);
        assert!(
            m.displacement < -1e-3,
            "heading {heading}: {}",
            m.displacement
        );
        assert!(
            m.lateral.abs() < 0.1 * m.displacement.abs(),
            "heading {heading}: {}",
            m.lateral
        );
    }
    // A 10° slope is within the friction angle (tan 10° = 0.18 < μ = 1): a body that does not
    // actuate stays where it settled, as on level ground, to within the jitter of a body at rest
    // (far below a micrometre, as above), where 50° moved it by millimetres.
    let mut still = scene(0.0, 10.0);
    if let Some(a) = still.dynamics.actuation.as_mut() {
        a.amplitude_volume = 0.0;
    }
    let m = walk(&still, &body);
    eprintln!("10° at rest: {}", m.displacement);
    assert!(m.displacement.abs() < 1e-6, "{}", m.displacement);
}

#[test]
fn the_incline_is_set_by_the_task_not_the_floor() {
    let mut s = scene(0.0, 0.0);
    s.dynamics.floor.as_mut().unwrap().incline = 0.1;
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("incline_degrees")
    );
    let s = scene(0.0, 95.0);
    assert!(
        s.validate()
            .unwrap_err()
            .to_string()
            .contains("incline_degrees")
    );
}
