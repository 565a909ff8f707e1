//! The `worker` binary's offline commands as a user runs them.

use std::path::{Path, PathBuf};
use std::process::Command;

fn worker(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_worker"))
        .args(args)
        .output()
        .expect("worker runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A chain of blobs along the beam (y) from the clamp to the tip, two materials.
const GENOME: &str = r#"{"points": [
  {"position": [0.5, 0.05, 0.5], "density": 1.0, "falloff": 0.12, "material": 0},
  {"position": [0.5, 0.3, 0.5], "density": 1.0, "falloff": 0.12, "material": 1},
  {"position": [0.5, 0.55, 0.5], "density": 1.0, "falloff": 0.12, "material": 0},
  {"position": [0.5, 0.8, 0.5], "density": 1.0, "falloff": 0.12, "material": 1},
  {"position": [0.5, 0.98, 0.5], "density": 1.0, "falloff": 0.3, "material": 0}
]}"#;

const SCENE: &str = "kind = \"beam\"\ntarget = \"circular_arc\"\n";

/// `worker export` of `genome` in the beam scene at 6x20x6, in a fresh folder named `test`;
/// returns success, stdout, stderr and the output folder.
fn export(test: &str, genome: &str) -> (bool, String, String, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("genome.json"), genome).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let out = dir.join("out");
    let (ok, stdout, stderr) = worker(&[
        "export",
        "--genome",
        dir.join("genome.json").to_str().unwrap(),
        "--scene",
        dir.join("scene.toml").to_str().unwrap(),
        "--resolution",
        "6x20x6",
        "--out",
        out.to_str().unwrap(),
    ]);
    (ok, stdout, stderr, out)
}

#[test]
fn export_writes_stl_per_material_vxa_and_one_svg_per_layer() {
    let (ok, stdout, stderr, out) = export("worker-export", GENOME);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("wrote"), "{stdout}");
    let design = std::fs::read_to_string(out.join("design.vxa")).unwrap();
    let back = amorph::export::read_vxa(&design).unwrap();
    assert_eq!(back.grid.dims(), amorph::voxel::GridDims::new(6, 20, 6));
    for z in 1..=6 {
        assert!(out.join(format!("layers/layer-{z:03}.svg")).is_file());
    }
    // One binary STL per material present: 84 + 50 bytes per triangle.
    let stls: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "stl"))
        .collect();
    let present = back
        .grid
        .material_counts(2)
        .iter()
        .filter(|&&c| c > 0)
        .count();
    assert!(present > 0);
    assert_eq!(stls.len(), present);
    for stl in stls {
        let bytes = std::fs::read(stl).unwrap();
        assert!(bytes.len() > 84 && (bytes.len() - 84).is_multiple_of(50));
    }
}

#[test]
fn an_out_of_range_genome_is_refused_naming_the_point_and_field() {
    let (ok, _, stderr, _) = export(
        "worker-out-of-range",
        &GENOME.replace(r#""falloff": 0.3"#, r#""falloff": 5.0"#),
    );
    assert!(!ok);
    assert!(
        stderr.contains("falloff") && stderr.contains("point 4"),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}

/// `worker evaluate --threads N`: a robot's outcome is the same JSON on 1 and 3 threads, and a
/// thread count out of range is refused in one line naming the flag.
#[test]
fn evaluate_prints_the_same_outcome_on_any_number_of_threads() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("worker-evaluate-threads");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let genome = r#"{"points": [
      {"position": [0.3, 0.5, 0.3], "density": 1.0, "falloff": 0.3, "material": 0},
      {"position": [0.7, 0.5, 0.3], "density": 1.0, "falloff": 0.3, "material": 1}
    ]}"#;
    let scene = "kind = \"locomotion\"\nworkspace = 0.02\nactuation_cycles = 2\n\
                 [settle]\nmax_time = 0.01\n[dynamics.actuation]\nperiod = 0.02\n";
    std::fs::write(dir.join("genome.json"), genome).unwrap();
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let evaluate = |threads: &str| {
        worker(&[
            "evaluate",
            "--genome",
            dir.join("genome.json").to_str().unwrap(),
            "--scene",
            dir.join("scene.toml").to_str().unwrap(),
            "--resolution",
            "10x10x10",
            "--threads",
            threads,
        ])
    };
    let (ok, alone, stderr) = evaluate("1");
    assert!(ok, "{stderr}");
    assert!(alone.contains("\"evaluated\""), "{alone}");
    let (ok, shared, stderr) = evaluate("3");
    assert!(ok, "{stderr}");
    assert_eq!(shared, alone);
    let (ok, _, stderr) = evaluate("0");
    assert!(!ok);
    assert!(stderr.contains("--threads 0"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}

/// A bad key deep in a scene file is refused in one line naming the file, the line and the key,
/// whether the file is a bare scene table or a run config, rather than with serde's message and
/// no line at all.
#[test]
fn a_bad_scene_file_is_refused_at_its_key() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("worker-bad-scene");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("genome.json"), GENOME).unwrap();
    let bare = "kind = \"locomotion\"\n[dynamics]\nlink_precision = \"single\"\n";
    let config = format!("name = \"x\"\nseed = 1\n\n[scene]\n{SCENE}lenght = 3\n");
    for (file, text, expect) in [
        (
            "bare.toml",
            bare.to_string(),
            "line 3: `link_precision = \"single\"`",
        ),
        (
            "config.toml",
            config,
            "line 7: `lenght = 3`: unknown field `lenght`",
        ),
    ] {
        let path = dir.join(file);
        std::fs::write(&path, text).unwrap();
        let (ok, _, stderr) = worker(&[
            "evaluate",
            "--genome",
            dir.join("genome.json").to_str().unwrap(),
            "--scene",
            path.to_str().unwrap(),
            "--resolution",
            "6x20x6",
        ]);
        assert!(!ok);
        assert!(stderr.contains(path.to_str().unwrap()), "{stderr}");
        assert!(stderr.contains(expect), "{file}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    }
}
