//! The locomotion task runs through the same coordinator, search and local evaluators as the beam
//! designer, deterministically, and writes a locomotion summary.

use std::path::Path;

use amorph::dynamics::{FrictionLaw, LinkPrecision};
use amorph::task::locomotion::LocomotionScene;
use amorph::task::{Metrics, Scene};
use amorph_coordinator::RunConfig;
use amorph_tests::{ClusterRun, run_locally, scratch_dir, test_config};

use crate::report_check;

/// A tiny walking-robot run: 4x4x4 designs, a short settle and two actuation cycles, so the test
/// checks the plumbing (scene parsing, evaluation, outcomes, results) in seconds, not the physics
/// (which `shared/tests/integration/dynamics_*.rs` check against analytic references).
fn tiny_locomotion_config(results_dir: &Path, seed: u64) -> RunConfig {
    test_config("locomotion_tiny", results_dir, &[&format!("seed={seed}")])
}

/// `cluster.threads_per_evaluation`: the coordinator's local workers run each evaluation inside a
/// pool of that many threads, and the run is the one the calling-thread evaluators give (the
/// simulation's own bit-identity across thread counts is `shared/tests/integration/dynamics_threads.rs`).
#[test]
fn local_workers_sharing_each_evaluation_among_threads_give_the_same_run() {
    let alone = {
        let dir = scratch_dir("walker-alone");
        run_locally(&tiny_locomotion_config(&dir, 9), 1)
    };
    let dir = scratch_dir("walker-shared");
    let mut config = tiny_locomotion_config(&dir, 9);
    config.cluster.threads_per_evaluation = 3;
    let shared = ClusterRun::start(&config, 2, None).join();
    assert_eq!(shared.evaluations, 20);
    assert_eq!(shared.populations, alone.populations);
}

#[test]
fn a_locomotion_run_evaluates_walkers_deterministically_and_summarises_them() {
    let one = {
        let dir = scratch_dir("walker-1");
        run_locally(&tiny_locomotion_config(&dir, 5), 1)
    };
    let dir = scratch_dir("walker-2");
    let config = tiny_locomotion_config(&dir, 5);
    let two = run_locally(&config, 2);
    assert_eq!(one.evaluations, 20);
    assert_eq!(one.populations, two.populations);

    // Every evaluated design reports finite locomotion metrics consistent with its fitness.
    let evaluated: Vec<_> = two
        .populations
        .iter()
        .flatten()
        .filter_map(|i| match i.outcome.metrics()? {
            Metrics::Locomotion(m) => Some((i.outcome.fitness()?, m)),
            _ => None,
        })
        .collect();
    assert!(!evaluated.is_empty(), "no design was evaluated");
    for (fitness, m) in &evaluated {
        assert_eq!(*fitness, m.gait_displacement);
        assert!(m.body_length > 0.0 && m.body_length <= 0.008 + 1e-12);
        assert_eq!(m.centre_of_mass_trace.len(), 3, "settled + 2 cycles");
        // Two cycles: the median of the per-cycle travels is their mean, so the gait travel is
        // the total travel up to rounding.
        let total = m.centre_of_mass_trace[2][0] - m.centre_of_mass_trace[0][0];
        assert!((m.displacement - total).abs() <= 1e-15);
        assert!((m.gait_displacement - total).abs() <= 1e-12 * total.abs().max(1e-6));
        let expected: f64 = 100.0 * m.gait_displacement / m.body_length / 2.0;
        assert!((m.speed_percent_per_cycle - expected).abs() <= 1e-12 * expected.abs().max(1.0));
    }

    let summary = std::fs::read_to_string(config.run_dir().join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(summary["task"], "locomotion");
    assert_eq!(summary["evaluations"], 20);

    // The report's Table-IV comparison holds this run's speed beside the paper's.
    let speed = summary["speed_percent_body_length_per_cycle"]
        .as_f64()
        .expect("an evaluated best");
    let md = report_check::check_report(
        &config.run_dir(),
        "speed (% body length per cycle)",
        &format!("{speed:.3} %"),
    );
    assert!(md.contains("| 3.38 % |"), "paper value missing");
    // The best robot's walk and trajectory are written and shown.
    for picture in ["animation.gif", "trajectory.png"] {
        assert!(
            md.contains(&format!("](<{picture}>)")),
            "{picture} not shown"
        );
    }
    let trajectory = std::fs::read_to_string(config.run_dir().join("trajectory.csv")).unwrap();
    // Header, settling checks, the settled sample, 20 samples per cycle for 2 cycles.
    assert!(trajectory.lines().count() >= 1 + 1 + 1 + 40);

    // The dashboard draws the best robot's track from its stored outcome, and shows its speed
    // beside the paper's.
    let status =
        amorph_tests::http::store_status(&amorph_coordinator::store::RunStore::path_for(&config));
    let best = &status["best"];
    assert_eq!(best["fitness"].as_f64(), two.best().outcome.fitness());
    let track = &best["outcome"]["evaluated"]["metrics"]["locomotion"]["centre_of_mass_trace"];
    assert_eq!(track.as_array().map(Vec::len), Some(3), "{best:#}");
    assert_eq!(
        best["summary"]["speed_percent_body_length_per_cycle"].as_f64(),
        Some(speed)
    );
    assert_eq!(
        best["summary"]["paper_speed_percent_body_length_per_cycle"],
        3.38
    );
    assert_eq!(status["run"]["figure"], "gait_mm");
}

/// A locomotion run config with nothing but what a parse needs; tests add their scene keys.
const SMALL_LOCOMOTION_RUN: &str = r#"
name = "x"
seed = 1
[search]
population = 4
[budget]
evaluations = 4
[resolution]
levels = [[4, 4, 4]]
[scene]
kind = "locomotion"
"#;

#[test]
fn a_locomotion_scene_with_a_bad_field_is_refused_by_name() {
    let text = format!(
        "{SMALL_LOCOMOTION_RUN}{}",
        r#"
[scene.dynamics]
actuation = { amplitude_volume = 0.0, period = 0.1, phase = 0.0 }
floor = { incline = 2.0 }
"#
    );
    let err = RunConfig::parse(&text, Path::new("bad.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("floor.incline"), "{err}");
}

/// The link kernel's precision is a dynamics key: `mixed` reads as the mixed-precision kernel and
/// what the run writes back reads the same; a value that is not a precision is one line naming
/// the file, the key's line and the values it may take; a config without it is the double kernel
/// and writes no such key.
#[test]
fn the_link_precision_is_a_dynamics_key() {
    let mixed = format!(
        "{SMALL_LOCOMOTION_RUN}{}",
        "\n[scene.dynamics]\nlink_precision = \"mixed\"\n"
    );
    let config = RunConfig::parse(&mixed, Path::new("mixed.toml")).unwrap();
    let Scene::Locomotion(scene) = &config.scene else {
        panic!("not a locomotion scene: {:?}", config.scene);
    };
    assert_eq!(scene.dynamics.link_precision, LinkPrecision::Mixed);
    assert!(scene.dynamics.actuation.is_some());
    let written = toml::to_string(&config.to_raw()).unwrap();
    let reread = RunConfig::parse(&written, Path::new("config.toml")).unwrap();
    assert_eq!(reread.scene, config.scene);

    let single = mixed.replace("\"mixed\"", "\"single\"");
    let err = RunConfig::parse(&single, Path::new("single.toml"))
        .unwrap_err()
        .to_string();
    // The key's own line and text, not the line of the `[scene]` table that holds it.
    let line = single
        .lines()
        .position(|l| l.starts_with("link_precision"))
        .unwrap()
        + 1;
    assert!(
        err.starts_with(&format!(
            "config single.toml, line {line}: `link_precision = \"single\"`"
        )) && err.contains("unknown variant `single`")
            && err.contains("`mixed`")
            && !err.contains('\n'),
        "{err}"
    );

    let plain = RunConfig::parse(SMALL_LOCOMOTION_RUN, Path::new("plain.toml")).unwrap();
    let Scene::Locomotion(scene) = &plain.scene else {
        panic!("not a locomotion scene");
    };
    assert_eq!(scene.dynamics.link_precision, LinkPrecision::Double);
    assert!(
        !toml::to_string(&plain.to_raw())
            .unwrap()
            .contains("link_precision")
    );
}

/// A config that changes one dynamics key keeps every other key the paper's, the actuation
/// included: before, a `[scene.dynamics]` table without `[scene.dynamics.actuation]` read as a robot
/// with no actuation, and the run was refused.
#[test]
fn a_dynamics_table_changes_only_the_keys_it_names() {
    let text = format!(
        "{SMALL_LOCOMOTION_RUN}{}",
        r#"
[scene.dynamics.floor]
friction = "voxcad"
actuated_contact = true
"#
    );
    let config = RunConfig::parse(&text, Path::new("voxcad.toml")).unwrap();
    let Scene::Locomotion(scene) = &config.scene else {
        panic!("not a locomotion scene: {:?}", config.scene);
    };
    let mut expected = LocomotionScene::default();
    let floor = expected.dynamics.floor.as_mut().unwrap();
    floor.friction = FrictionLaw::Voxcad;
    floor.actuated_contact = true;
    assert_eq!(scene, &expected);
    assert!(scene.dynamics.actuation.is_some());
    // What the run writes back reads as the same scene.
    let written = toml::to_string(&config.to_raw()).unwrap();
    let reread = RunConfig::parse(&written, Path::new("config.toml")).unwrap();
    assert_eq!(reread.scene, config.scene);
}
