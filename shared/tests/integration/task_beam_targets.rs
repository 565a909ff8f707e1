//! Custom beam targets: points or a CSV file, joined linearly or by PCHIP, normalized, validated
//! with the point or the file and line named, and written back unchanged.

use amorph::task::beam::{CustomProfile, Interpolation, NamedProfile, TargetProfile};
use amorph::task::{Scene, Task};
use proptest::prelude::*;

fn custom(points: &[[f64; 2]], interpolation: Interpolation) -> CustomProfile {
    CustomProfile::from_points(points.to_vec(), interpolation).expect("a valid profile")
}

#[test]
fn pchip_agrees_with_scipy() {
    // Values of scipy.interpolate.PchipInterpolator (SciPy 1.16), an independent implementation
    // of the same Fritsch–Carlson scheme, at the same points.
    type Case<'a> = (&'a [[f64; 2]], &'a [(f64, f64)]);
    let cases: [Case; 2] = [
        (
            &[[0.0, 0.0], [0.3, 0.05], [0.7, 0.6], [1.0, 1.0]],
            &[
                (0.1, 0.0065940630456759524),
                (0.25, 0.03634489017553534),
                (0.5, 0.27168727225167033),
                (0.65, 0.5261455515335661),
                (0.85, 0.801401707278812),
                (0.95, 0.9340889405013673),
            ],
        ),
        (
            // Not monotone: a local maximum at 0.2 and minimum at 0.5 get zero slope.
            &[[0.0, 0.0], [0.2, 0.3], [0.5, 0.25], [0.6, 0.7], [1.0, 1.0]],
            &[
                (0.1, 0.20416666666666664),
                (0.3, 0.28703703703703703),
                (0.45, 0.2537037037037037),
                (0.55, 0.4562500000000004),
                (0.8, 0.9250000000000002),
            ],
        ),
    ];
    for (points, expected) in cases {
        let p = custom(points, Interpolation::Pchip);
        for &(t, f) in expected {
            assert!(
                (p.deflection(t) - f).abs() < 1e-12,
                "t = {t}: {} vs {f}",
                p.deflection(t)
            );
        }
    }
}

#[test]
fn a_sampled_arc_is_the_arc_within_the_interpolation_error() {
    // Linear interpolation of f = t² on a grid of step h errs by at most h²/8 · max|f''| = h²/4.
    let n = 200;
    let h = 1.0 / n as f64;
    let points: Vec<[f64; 2]> = (0..=n).map(|i| i as f64 * h).map(|t| [t, t * t]).collect();
    let linear = custom(&points, Interpolation::Linear);
    let pchip = custom(&points, Interpolation::Pchip);
    let arc = TargetProfile::Named(NamedProfile::CircularArc);
    for i in 0..=1000 {
        let t = i as f64 / 1000.0;
        assert!((linear.deflection(t) - arc.deflection(t)).abs() <= h * h / 4.0 + 1e-15);
        // PCHIP's slopes are first-order accurate, so its error is O(h²) too.
        assert!((pchip.deflection(t) - arc.deflection(t)).abs() <= h * h);
    }
}

#[test]
fn deflections_in_any_unit_are_normalized_to_clamp_0_and_tip_1() {
    let mm = custom(&[[0.0, 2.0], [0.5, 3.0], [1.0, 6.0]], Interpolation::Linear);
    assert_eq!(mm.deflection(0.0), 0.0);
    assert_eq!(mm.deflection(1.0), 1.0);
    assert_eq!(mm.deflection(0.5), 0.25);
}

proptest! {
    /// On monotone data PCHIP never overshoots: the curve is monotone and stays between the
    /// neighbouring points, and it passes through every point.
    #[test]
    fn pchip_is_monotone_on_monotone_data(steps in prop::collection::vec((0.01f64..1.0, 0.0f64..1.0), 1..12)) {
        let total_t: f64 = steps.iter().map(|s| s.0).sum();
        let total_f: f64 = steps.iter().map(|s| s.1).sum::<f64>() + 1e-3;
        let mut points = vec![[0.0, 0.0]];
        let (mut t, mut f) = (0.0, 0.0);
        for (i, (dt, df)) in steps.iter().enumerate() {
            t += dt / total_t;
            f += df / total_f;
            points.push([if i + 1 == steps.len() { 1.0 } else { t }, f]);
        }
        let f_tip = points.last().unwrap()[1];
        let p = custom(&points, Interpolation::Pchip);
        for w in points.windows(2) {
            prop_assert!((p.deflection(w[0][0]) - w[0][1] / f_tip).abs() < 1e-12);
        }
        let mut last = p.deflection(0.0);
        for i in 1..=2000 {
            let v = p.deflection(i as f64 / 2000.0);
            prop_assert!(v >= last - 1e-12, "drops at {}", i as f64 / 2000.0);
            last = v;
        }
    }
}

#[test]
fn bad_points_are_refused_by_index() {
    let bad = |points: &[[f64; 2]]| {
        CustomProfile::from_points(points.to_vec(), Interpolation::Pchip)
            .unwrap_err()
            .to_string()
    };
    let e = bad(&[[0.0, 0.0], [0.5, 0.3], [0.4, 0.5], [1.0, 1.0]]);
    assert!(
        e.contains("points[2]") && e.contains("does not increase"),
        "{e}"
    );
    let e = bad(&[[0.0, 0.0], [1.5, 1.0]]);
    assert!(
        e.contains("points[1]") && e.contains("outside [0, 1]"),
        "{e}"
    );
    let e = bad(&[[0.0, 0.0], [0.5, f64::NAN], [1.0, 1.0]]);
    assert!(e.contains("points[1]") && e.contains("not finite"), "{e}");
    let e = bad(&[[0.1, 0.0], [1.0, 1.0]]);
    assert!(e.contains("from 0 (clamp) to 1 (tip)"), "{e}");
    let e = bad(&[[0.0, 0.0]]);
    assert!(e.contains("2 to 10000 points"), "{e}");
    let e = bad(&[[0.0, 1.0], [0.5, 2.0], [1.0, 1.0]]);
    assert!(e.contains("cannot be normalized"), "{e}");
}

fn beam_with_target(target: &str) -> Result<Scene, String> {
    let text = format!("kind = \"beam\"\ntarget = {target}\n");
    toml::from_str::<Scene>(&text).map_err(|e| e.message().to_string())
}

#[test]
fn a_csv_profile_loads_relative_to_the_config_and_errors_name_file_and_line() {
    let dir = std::env::temp_dir().join(format!("amorph-csv-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("profiles")).unwrap();
    std::fs::write(
        dir.join("profiles/s.csv"),
        "# an S-shaped profile\nposition,deflection\n0,0\n0.25,0.1\n\n0.75,0.9\n1,1\n",
    )
    .unwrap();
    let mut scene =
        beam_with_target(r#"{ csv = "profiles/s.csv", interpolation = "linear" }"#).unwrap();
    scene.load_files(&dir).unwrap();
    scene.validate().unwrap();
    let Scene::Beam(beam) = &scene else { panic!() };
    assert_eq!(beam.target.label(), "profiles/s.csv");
    assert_eq!(beam.target.paper_rms_percent(), None);
    assert!((beam.target.deflection(0.5) - 0.5).abs() < 1e-15);
    // Loaded once, the points travel with the scene: a worker never reads the file.
    let json = serde_json::to_string(&scene).unwrap();
    assert!(json.contains("\"points\""), "{json}");
    let back: Scene = serde_json::from_str(&json).unwrap();
    assert_eq!(back, scene);

    std::fs::write(dir.join("profiles/bad.csv"), "0,0\n0.5,0.2\n0.4,0.6\n1,1\n").unwrap();
    let mut scene = beam_with_target(r#"{ csv = "profiles/bad.csv" }"#).unwrap();
    let e = scene.load_files(&dir).unwrap_err().to_string();
    assert!(
        e.contains("bad.csv line 3") && e.contains("does not increase"),
        "{e}"
    );
    std::fs::write(dir.join("profiles/junk.csv"), "0,0\n0.5,x\n1,1\n").unwrap();
    let mut scene = beam_with_target(r#"{ csv = "profiles/junk.csv" }"#).unwrap();
    let e = scene.load_files(&dir).unwrap_err().to_string();
    assert!(e.contains("junk.csv line 2"), "{e}");
    let mut scene = beam_with_target(r#"{ csv = "profiles/missing.csv" }"#).unwrap();
    let e = scene.load_files(&dir).unwrap_err().to_string();
    assert!(e.contains("missing.csv"), "{e}");
    // Never loaded (a scene read without its config's folder): refused, not evaluated blind.
    let e = beam_with_target(r#"{ csv = "profiles/s.csv" }"#)
        .unwrap()
        .validate()
        .unwrap_err();
    assert!(e.to_string().contains("target.csv"), "{e}");
}

#[test]
fn targets_are_written_as_configs_write_them() {
    // A named target stays a bare name (stored configs and scene hashes unchanged).
    let scene = beam_with_target(r#""circular_arc""#).unwrap();
    assert!(
        serde_json::to_string(&scene)
            .unwrap()
            .contains("\"target\":\"circular_arc\"")
    );
    let e = beam_with_target(r#""circular_ark""#).unwrap_err();
    assert!(e.contains("circular_ark") && e.contains("straight"), "{e}");
    let e =
        beam_with_target(r#"{ points = [[0.0, 0.0], [1.0, 1.0]], smoothing = 2 }"#).unwrap_err();
    assert!(e.contains("smoothing"), "{e}");
    // Integers are positions too.
    let scene = beam_with_target("{ points = [[0, 0], [0.5, 0.2], [1, 1]] }").unwrap();
    scene.validate().unwrap();
    let Scene::Beam(beam) = &scene else { panic!() };
    assert_eq!(beam.target.label(), "custom (3 points)");
    assert!(beam.palette().len() == 2);
}
