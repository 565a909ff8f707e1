//! The `worker` binary's offline commands as a user runs them.

use std::path::Path;
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

const GENOME: &str = r#"{"points": [
  {"position": [0.5, 0.5, 0.5], "density": 1.0, "falloff": 0.3, "material": 0},
  {"position": [0.5, 0.9, 0.5], "density": 0.8, "falloff": 0.1, "material": 1}
]}"#;

const SCENE: &str = "kind = \"beam\"\ntarget = \"circular_arc\"\n";

#[test]
fn export_writes_stl_per_material_vxa_and_one_svg_per_layer() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("worker-export");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("genome.json"), GENOME).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let out = dir.join("out");
    let (ok, stdout, stderr) = worker(&[
        "export",
        "--genome",
        dir.join("genome.json").to_str().unwrap(),
        "--scene",
        dir.join("scene.toml").to_str().unwrap(),
        "--resolution",
        "6x6x20",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("wrote"), "{stdout}");
    let design = std::fs::read_to_string(out.join("design.vxa")).unwrap();
    let back = amorph::export::read_vxa(&design).unwrap();
    assert_eq!(back.grid.dims().nz, 20);
    for z in 1..=20 {
        assert!(out.join(format!("layers/layer-{z:03}.svg")).is_file());
    }
    // Binary STL size is 84 + 50 bytes per triangle, and a beam of material 0 is present.
    let stl = std::fs::read(out.join("material-0-hard-resin.stl")).unwrap();
    assert!(stl.len() > 84 && (stl.len() - 84).is_multiple_of(50));
}

#[test]
fn an_out_of_range_genome_is_refused_naming_the_point_and_field() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("worker-nan");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("genome.json"), GENOME.replace("0.3", "5.0")).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let (ok, _, stderr) = worker(&[
        "export",
        "--genome",
        dir.join("genome.json").to_str().unwrap(),
        "--scene",
        dir.join("scene.toml").to_str().unwrap(),
        "--resolution",
        "6x6x20",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("falloff") && stderr.contains("point 0"),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}
