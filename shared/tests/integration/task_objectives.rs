//! Each task's objectives, as a multi-objective search reads them: named once each, and valued from
//! an evaluation's metrics exactly as counting the evaluated design's voxels gives them.

use amorph::genome::random_genome;
use amorph::task::objectives::{mass, stiffest};
use amorph::task::{Metrics, Scene, Sense};
use amorph::voxel::{GridDims, VoxelGrid};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn scene(toml: &str) -> Scene {
    toml::from_str(toml).unwrap()
}

/// Voxels of each material in a grid, counted cell by cell.
fn counts(grid: &VoxelGrid, materials: usize) -> Vec<usize> {
    let mut counts = vec![0; materials];
    for m in grid.cells().iter().flatten() {
        counts[m.index()] += 1;
    }
    counts
}

/// The first `n` random designs of `scene` at `dims` that evaluate, with their kept voxels and
/// objective values.
fn evaluated(scene: &Scene, dims: GridDims, n: usize) -> Vec<(VoxelGrid, Metrics, Vec<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut found = Vec::new();
    for _ in 0..200 {
        let genome = random_genome(&mut rng, 20, scene.limits(), scene.palette().len());
        let outcome = scene.evaluate(&genome, dims);
        let Some(values) = scene.objective_values(&outcome, dims) else {
            continue;
        };
        let metrics = outcome.metrics().unwrap().clone();
        found.push((scene.design(&genome, dims), metrics, values));
        if found.len() == n {
            return found;
        }
    }
    panic!("fewer than {n} of 200 random designs evaluated");
}

#[test]
fn each_task_names_its_objectives_once() {
    for (toml, names) in [
        (
            "kind = \"beam\"\ntarget = \"straight\"",
            &["rms", "hard_fraction", "voxels", "mass"][..],
        ),
        (
            "kind = \"locomotion\"",
            &["speed", "voxels", "actuated_fraction"],
        ),
        ("kind = \"stiffness\"", &["compliance", "hard_fraction"]),
    ] {
        let objectives = scene(toml).objectives();
        let listed: Vec<&str> = objectives.iter().map(|o| o.name).collect();
        assert_eq!(listed, names);
        let speed = objectives.iter().find(|o| o.name == "speed");
        assert!(speed.is_none_or(|o| o.sense == Sense::Maximize));
        assert!(
            (objectives.iter())
                .filter(|o| o.name != "speed")
                .all(|o| o.sense == Sense::Minimize)
        );
    }
}

#[test]
fn a_beams_objectives_are_its_error_and_what_its_voxels_weigh() {
    let beam = scene("kind = \"beam\"\ntarget = \"circular_arc\"");
    let dims = GridDims::new(6, 20, 6);
    let palette = beam.palette();
    let size = beam.voxel_size(dims);
    for (grid, metrics, values) in evaluated(&beam, dims, 3) {
        let Metrics::Beam(m) = metrics else {
            panic!("a beam's metrics")
        };
        let counts = counts(&grid, palette.len());
        let hard = counts[stiffest(palette)] as f64 / dims.cell_count() as f64;
        let weight: f64 = (counts.iter().zip(&palette.0))
            .map(|(&c, material)| c as f64 * material.density * size.powi(3))
            .sum();
        assert_eq!(values[0], m.rms_percent);
        assert_eq!(values[1], hard);
        assert_eq!(values[2], grid.cells().iter().flatten().count() as f64);
        assert!((values[3] - weight).abs() <= 1e-12 * weight, "{values:?}");
        assert_eq!(values[3], mass(&counts, palette, size));
    }
}

#[test]
fn a_stiffness_designs_objectives_are_its_compliance_and_hard_share() {
    let stiffness = scene("kind = \"stiffness\"");
    let Scene::Stiffness(s) = &stiffness else {
        panic!("a stiffness scene")
    };
    let dims = GridDims::new(4, 12, 4);
    for (grid, metrics, values) in evaluated(&stiffness, dims, 3) {
        let Metrics::Stiffness(m) = metrics else {
            panic!("stiffness metrics")
        };
        let hard = counts(&grid, s.palette.len())[usize::from(s.hard_material)];
        assert_eq!(
            values,
            vec![s.tip_load * m.tip_deflection, hard as f64 / 192.0]
        );
    }
}

#[test]
fn a_robots_objectives_are_its_gait_its_size_and_its_actuated_share() {
    let robot = scene("kind = \"locomotion\"");
    let palette = robot.palette();
    let dims = GridDims::new(5, 5, 5);
    for (grid, metrics, values) in evaluated(&robot, dims, 2) {
        let Metrics::Locomotion(m) = metrics else {
            panic!("a robot's metrics")
        };
        let counts = counts(&grid, palette.len());
        let voxels: usize = counts.iter().sum();
        let actuated: usize = (counts.iter().zip(&palette.0))
            .filter(|(_, material)| material.actuated)
            .map(|(c, _)| c)
            .sum();
        assert_eq!(values[0], 1e3 * m.gait_displacement);
        assert_eq!(values[1], voxels as f64);
        assert_eq!(values[2], actuated as f64 / voxels as f64);
    }
}
