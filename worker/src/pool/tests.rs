use super::*;
use amorph::genome::GaussianPoint;
use amorph::material::MaterialId;
use amorph::task::locomotion::LocomotionScene;

/// A two-foam robot in a 10³ workspace (about 350 voxels, several parts per thread), walked
/// for two short cycles.
fn job(task: u64) -> Job {
    let blob = |x: f64, material: u8| GaussianPoint {
        position: [x, 0.5, 0.3],
        density: 1.0,
        falloff: 0.3,
        material: MaterialId(material),
    };
    let mut scene = LocomotionScene {
        workspace: 0.02,
        ..LocomotionScene::default()
    };
    scene.actuation_cycles = 2;
    scene.settle.max_time = 0.01;
    if let Some(a) = scene.dynamics.actuation.as_mut() {
        a.period = 0.02;
    }
    Job {
        task_id: TaskId(task),
        genome: Genome::new(vec![blob(0.3, 0), blob(0.7, 1)]),
        scene: Arc::new(Scene::Locomotion(scene)),
        dims: GridDims::new(10, 10, 10),
    }
}

fn evaluate_on(per_evaluation: usize) -> String {
    let (done, mut finished) = tokio::sync::mpsc::unbounded_channel();
    let pool = Pool::new(1, per_evaluation, EvaluationMode::Physics, done).unwrap();
    pool.submit(job(7));
    let outcome = finished.blocking_recv().unwrap().outcome;
    serde_json::to_string(&outcome).unwrap()
}

#[test]
fn an_evaluation_shared_by_threads_is_the_same_bits() {
    let alone = evaluate_on(1);
    assert!(alone.starts_with("{\"evaluated\""), "{alone}");
    assert_eq!(evaluate_on(3), alone);
}
