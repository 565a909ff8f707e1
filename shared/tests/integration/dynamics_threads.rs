//! Several threads for one simulation (`dynamics::parallel`): a step run inside a thread pool gives
//! the bits of the same step on one thread, for any number of threads, through a walk on the
//! floor (friction, actuation, link damping), with the Poisson coupling and self-collision on,
//! with the mixed-precision link kernel, and for a whole locomotion evaluation.

use amorph::dynamics::{DynamicScene, LinkPrecision, Simulation, foam_palette};
use amorph::material::MaterialId;
use amorph::task::Scene;
use amorph::task::locomotion::simulate_locomotion;
use amorph::voxel::{GridDims, VoxelGrid};

use crate::common;

/// A 14×9×6 body (about 700 voxels and 1,900 links, so several parts of each at the parallel
/// pass's grain) with holes, so that the link pass meets both runs of four and scattered links:
/// passive at −x, actuated at +x.
fn body() -> VoxelGrid {
    let dims = GridDims::new(14, 9, 6);
    let cells = (0..dims.cell_count())
        .map(|i| {
            let [x, y, z] = dims.coords(i);
            let hole = (7 * x + 3 * y + 5 * z) % 11 == 0 && z > 0;
            (!hole).then_some(MaterialId(u8::from(x >= 7)))
        })
        .collect();
    VoxelGrid::from_cells(dims, cells)
}

/// Every bit of the state after `steps` steps, on the calling thread or inside a pool of
/// `threads` threads.
fn run(scene: &DynamicScene, steps: u64, threads: Option<usize>) -> Vec<u64> {
    let simulate = || {
        let mut sim = Simulation::new(&body(), &foam_palette(), scene).unwrap();
        sim.start_actuation();
        sim.run_steps(steps).unwrap();
        let mut bits = vec![sim.time().to_bits()];
        for p in sim.positions().iter().chain(sim.velocities()) {
            bits.extend([p.x, p.y, p.z].map(f64::to_bits));
        }
        for q in sim.orientations() {
            bits.extend([q.w, q.x, q.y, q.z].map(f64::to_bits));
        }
        bits
    };
    match threads {
        None => simulate(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(simulate),
    }
}

fn threads_agree(scene: &DynamicScene, steps: u64) {
    let one = run(scene, steps, None);
    let start = run(scene, 0, None);
    assert_ne!(one, start, "the body must move");
    for threads in [1, 2, 3] {
        assert!(
            run(scene, steps, Some(threads)) == one,
            "{threads} threads changed the bits"
        );
    }
}

#[test]
fn threads_give_the_bits_of_one_thread() {
    // About a quarter of an actuation period: the body lands, presses on the floor and swells.
    let scene = DynamicScene {
        voxel_size: 0.002,
        ..DynamicScene::paper_locomotion()
    };
    threads_agree(&scene, 1500);
}

#[test]
fn threads_give_the_bits_of_one_thread_with_poisson_coupling_and_collisions() {
    let scene = DynamicScene {
        voxel_size: 0.002,
        poisson: true,
        collisions: true,
        ..DynamicScene::paper_locomotion()
    };
    threads_agree(&scene, 600);
}

#[test]
fn a_locomotion_evaluation_is_the_same_on_any_number_of_threads() {
    let (genome, scene, dims) = common::short_walker();
    let body = amorph::task::design(&scene, &genome, dims);
    let evaluate = || {
        let outcome = simulate_locomotion(
            &body,
            &scene.palette,
            &scene.dynamics_at(dims),
            &scene.protocol(),
        );
        serde_json::to_string(&outcome).unwrap()
    };
    let one = evaluate();
    for threads in [2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        assert_eq!(pool.install(evaluate), one, "{threads} threads");
    }
    // The task's own entry point, as a worker calls it.
    let scene = Scene::Locomotion(scene);
    let task = || serde_json::to_string(&scene.evaluate(&genome, dims)).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    assert_eq!(pool.install(task), task());
}

#[test]
fn threads_give_the_bits_of_one_thread_with_the_mixed_precision_kernel() {
    let scene = DynamicScene {
        voxel_size: 0.002,
        link_precision: LinkPrecision::Mixed,
        ..DynamicScene::paper_locomotion()
    };
    threads_agree(&scene, 1500);
}
