use std::sync::Arc;

use amorph::task::beam::BeamMetrics;
use amorph::task::{Metrics, Outcome, Scene};
use amorph::voxel::GridDims;

use super::*;
use crate::search::fixtures::failed;

const DIMS: GridDims = GridDims {
    nx: 4,
    ny: 12,
    nz: 4,
};

/// A beam's RMS error and voxel count traded off, the reference point at (10 %, 100 voxels).
fn pareto(selection: Selection) -> Pareto {
    let scene: Scene = toml::from_str("kind = \"beam\"\ntarget = \"straight\"").unwrap();
    Pareto::new(
        Arc::new(scene),
        &["rms".into(), "voxels".into()],
        selection,
        &[10.0, 100.0],
        DIMS,
    )
}

/// A beam design with this RMS error (%) and this many (soft) voxels.
fn design(rms: f64, voxels: usize) -> Outcome {
    Outcome::evaluated(
        -rms,
        Metrics::Beam(BeamMetrics {
            rms_percent: rms,
            tip_deflection: 1e-3,
            voxels,
            material_counts: vec![0, voxels],
            surface_voxels: 1,
            profile: Vec::new(),
            solver_iterations: 0,
            solver_residual: 0.0,
        }),
    )
}

#[test]
fn an_outcome_is_its_objectives_and_a_failure_is_dominated_by_all() {
    let p = pareto(Selection::Crowding);
    assert_eq!(p.values(&design(1.5, 30)), Some(vec![1.5, 30.0]));
    assert_eq!(p.point(&design(1.5, 30)), vec![1.5, 30.0]);
    assert_eq!(p.values(&failed()), None);
    assert!(dominates(&p.point(&design(9.0, 99)), &p.point(&failed())));
}

/// A child that dominates its parent replaces it, one it dominates does not; a trade-off with its
/// parent takes the slot only where it would stand better: here the parent (2.5, 9) is dominated
/// by (2, 5) and the child (0.8, 12) by nobody, so the child stands a front higher.
#[test]
fn crowding_replaces_by_dominance_then_by_standing() {
    let p = pareto(Selection::Crowding);
    let population = [
        design(1.0, 10),
        design(2.0, 5),
        design(3.0, 3),
        design(2.5, 9),
    ];
    let occupants: Vec<&Outcome> = population.iter().collect();
    assert!(p.replaces(&occupants, 0, &design(0.5, 8)));
    assert!(!p.replaces(&occupants, 0, &design(2.0, 12)));
    assert!(
        !p.replaces(&occupants, 0, &design(1.0, 10)),
        "an equal design"
    );
    assert!(p.replaces(&occupants, 3, &design(0.8, 12)));
    // (1.5, 10) is dominated by (1, 10): it would stand in the parent's front, alone, as the
    // parent does, so no gain.
    assert!(!p.replaces(&occupants, 3, &design(1.5, 10)));
    // A trade-off that would stand where its parent stands, with less room: (1, 10) is the
    // front's end in voxels (infinite room); (0.5, 20) would be the end too, so no gain.
    assert!(!p.replaces(&occupants, 0, &design(0.5, 20)));
    assert!(!p.replaces(&occupants, 0, &failed()));
}

#[test]
fn nsga2_keeps_whole_fronts_then_the_roomiest() {
    let p = pareto(Selection::Nsga2);
    // Front 0: (1, 9), (2, 5), (4, 2), (3, 4); front 1: (3, 6); then a failure.
    let all = [
        design(3.0, 6),
        design(1.0, 9),
        failed(),
        design(2.0, 5),
        design(4.0, 2),
        design(3.0, 4),
    ];
    let refs: Vec<&Outcome> = all.iter().collect();
    assert_eq!(p.survivors(&refs, 5), vec![0, 1, 3, 4, 5]);
    // Cut to three, the ends (1, 9) and (4, 2) stay, and of the two inside (2, 5) has room
    // (3 − 1)/3 + (9 − 4)/7 against (3, 4)'s (4 − 2)/3 + (5 − 2)/7: (2, 5) stays.
    assert_eq!(p.survivors(&refs, 3), vec![1, 3, 4]);
    assert_eq!(p.ranked(&refs)[..4], [1, 4, 3, 5]);
    assert_eq!(
        *p.ranked(&refs).last().unwrap(),
        2,
        "the failure stands last"
    );
}

/// The front of a run's evaluations: dominated, failed and repeated designs left out (a repeat
/// counted as its first evaluation), members in task order, and its hypervolume the union of
/// their boxes up to the reference point (10, 100).
#[test]
fn the_front_of_a_runs_evaluations() {
    let p = pareto(Selection::Crowding);
    let evaluations = [
        (TaskId(7), design(2.0, 50)),
        (TaskId(3), design(1.0, 90)),
        (TaskId(5), design(3.0, 60)),
        (TaskId(9), design(2.0, 50)),
        (TaskId(4), failed()),
        (TaskId(8), design(6.0, 20)),
        (TaskId(2), design(11.0, 1)),
    ];
    let front = p.front(evaluations.iter().map(|(t, o)| (*t, o)));
    assert_eq!(
        front.members,
        vec![
            (TaskId(2), vec![11.0, 1.0]),
            (TaskId(3), vec![1.0, 90.0]),
            (TaskId(7), vec![2.0, 50.0]),
            (TaskId(8), vec![6.0, 20.0]),
        ]
    );
    assert_eq!(
        front.objectives.iter().map(|o| o.name).collect::<Vec<_>>(),
        ["rms", "voxels"]
    );
    // (11, 1) lies outside the reference box; the others add strips by rms:
    // (10 − 1)(100 − 90) + (10 − 2)(90 − 50) + (10 − 6)(50 − 20) = 90 + 320 + 120.
    assert_eq!(front.hypervolume, 530.0);
}
