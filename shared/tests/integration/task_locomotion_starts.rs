//! Several starts of one settled robot (`[scene.starts]`): each start is exactly the robot
//! evaluated alone with its shifted phase (the shared settle changes nothing), the fitness and
//! every reported field are the median start's, watching it changes nothing, and a peer's claimed
//! starts are checked.

use amorph::task::Task;
use amorph::task::locomotion::{
    LocomotionMetrics, LocomotionOutcome, LocomotionPhase, LocomotionScene, LocomotionStatus,
    Starts, simulate_locomotion, simulate_locomotion_observed,
};
use amorph::voxel::{GridDims, VoxelGrid};

use crate::common;

/// The short walker of the export tests, switched on three times a tenth of a period apart, far
/// enough for three different gaits.
fn walker() -> (VoxelGrid, LocomotionScene, GridDims) {
    let (genome, scene, dims) = common::short_walker();
    let scene = LocomotionScene {
        starts: Starts {
            count: 3,
            shift: 0.1,
        },
        ..scene
    };
    (amorph::task::design(&scene, &genome, dims), scene, dims)
}

/// The same robot evaluated once, its actuation starting at start `k`'s phase.
fn alone(body: &VoxelGrid, scene: &LocomotionScene, dims: GridDims, k: usize) -> LocomotionOutcome {
    let mut dynamics = scene.dynamics_at(dims);
    if let Some(a) = dynamics.actuation.as_mut() {
        a.phase += scene.starts.phase(k);
    }
    let protocol = LocomotionScene {
        starts: Starts::default(),
        ..scene.clone()
    }
    .protocol();
    simulate_locomotion(body, &scene.palette, &dynamics, &protocol)
}

#[test]
fn each_start_is_the_robot_switched_on_alone_and_the_median_start_is_reported() {
    let (body, scene, dims) = walker();
    let outcome = simulate_locomotion(
        &body,
        &scene.palette,
        &scene.dynamics_at(dims),
        &scene.protocol(),
    );
    assert_eq!(outcome.status, LocomotionStatus::Completed);
    let singles: Vec<LocomotionOutcome> = (0..3).map(|k| alone(&body, &scene, dims, k)).collect();
    let each: Vec<f64> = singles.iter().map(|o| o.fitness).collect();
    assert_eq!(outcome.start_fitness, each, "bit for bit, start by start");
    assert!(
        each[0] != each[1] && each[1] != each[2] && each[0] != each[2],
        "the setup must give three different gaits: {each:?}"
    );
    let mut sorted = each.clone();
    sorted.sort_by(f64::total_cmp);
    assert_eq!(outcome.fitness, sorted[1]);
    let median = Starts::median_start(&each);
    let reported = LocomotionOutcome {
        start_fitness: Vec::new(),
        ..outcome.clone()
    };
    assert_eq!(
        reported, singles[median],
        "every field is the median start's"
    );
}

#[test]
fn watching_several_starts_changes_nothing_and_sees_the_median_one() {
    let (body, scene, dims) = walker();
    let (dynamics, protocol) = (scene.dynamics_at(dims), scene.protocol());
    let plain = simulate_locomotion(&body, &scene.palette, &dynamics, &protocol);
    let (mut settled, mut last_sample) = (0, None);
    let observed = simulate_locomotion_observed(
        &body,
        &scene.palette,
        &dynamics,
        &protocol,
        4,
        &mut |p, s| match p {
            LocomotionPhase::Settled => settled += 1,
            LocomotionPhase::Actuating { .. } => last_sample = Some(s.centre_of_mass()),
            LocomotionPhase::Settling => {}
        },
    );
    assert_eq!(plain, observed);
    assert_eq!(settled, 1, "one settle for all starts");
    let end = last_sample.expect("actuation was watched");
    assert_eq!(
        [end.x, end.y, end.z],
        *plain.centre_of_mass_trace.last().unwrap()
    );
}

#[test]
fn a_peers_starts_must_be_one_per_start_with_the_fitness_their_median() {
    let (body, scene, dims) = walker();
    let outcome = scene.simulate(&body);
    let (fitness, metrics): (f64, LocomotionMetrics) = (
        outcome.fitness().expect("evaluated"),
        outcome.metrics().expect("evaluated").clone(),
    );
    assert_eq!(scene.check_metrics(fitness, &metrics, dims), Ok(()));
    let claim = |f: fn(&mut Vec<f64>)| {
        let mut m = metrics.clone();
        f(&mut m.start_fitness);
        scene.check_metrics(fitness, &m, dims)
    };
    let fewer = claim(|s| {
        s.pop();
    });
    assert!(fewer.unwrap_err().0.contains("start_fitness has 2 values"));
    let median = Starts::median_start(&metrics.start_fitness);
    let lifted = {
        let mut m = metrics.clone();
        let top = m.start_fitness.iter().copied().fold(f64::MIN, f64::max);
        m.start_fitness[median] = top + 1e-3;
        scene.check_metrics(fitness, &m, dims)
    };
    assert!(
        lifted
            .unwrap_err()
            .0
            .contains("is not the scored start's gait")
    );
    let far = claim(|s| s[0] = 1e9);
    assert!(far.unwrap_err().0.contains("beyond what"));
    let single = LocomotionScene {
        starts: Starts::default(),
        ..scene.clone()
    };
    let stray = single.check_metrics(fitness, &metrics, dims);
    assert!(stray.unwrap_err().0.contains("expected 0"));
}
