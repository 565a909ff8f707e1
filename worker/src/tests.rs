use super::*;

/// A bad genome file (`material: 300`, a NaN) is refused naming the field, not with serde's
/// "data did not match any variant of untagged enum GenomeFile" or "expected value at line 1
/// column 27".
#[test]
fn a_bad_genome_file_names_the_field() {
    let dir = std::env::temp_dir().join(format!("amorph-genome-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let point = r#"{"position": [0.5, 0.5, 0.5], "density": 1.0, "falloff": 0.1, "material": 1}"#;
    let cases = [
        (format!(r#"{{"points": [{point}]}}"#), None),
        (
            format!(r#"{{"fitness": 1.0, "genome": {{"points": [{point}]}}}}"#),
            None,
        ),
        (
            format!(
                r#"{{"points": [{point}, {}]}}"#,
                point.replace(": 1}", ": 300}")
            ),
            Some("points[1].material = 300"),
        ),
        (
            format!(
                r#"{{"genome": {{"points": [{}]}}}}"#,
                point.replace("1.0", "NaN")
            ),
            Some("NaN or Infinity"),
        ),
        (
            format!(
                r#"{{"points": [{}]}}"#,
                point.replace(r#""falloff": 0.1, "#, "")
            ),
            Some("the genome.points[0].falloff is missing"),
        ),
        (
            r#"{"points": 3}"#.to_owned(),
            Some("points is missing or not a list"),
        ),
    ];
    for (i, (text, error)) in cases.iter().enumerate() {
        let path = dir.join(format!("{i}.json"));
        std::fs::write(&path, text).unwrap();
        match (read_genome(&path), error) {
            (Ok(g), None) => assert_eq!(g.points.len(), 1),
            (Err(e), Some(expected)) => {
                let e = e.to_string();
                assert!(e.contains(expected), "{text}: {e}");
            }
            (other, _) => panic!("{text}: {:?}", other.map(|g| g.points.len())),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resolutions_parse_strictly() {
    assert_eq!(
        parse_resolution("12x12x40").unwrap(),
        GridDims::new(12, 12, 40)
    );
    for bad in [
        "12x12",
        "0x1x1",
        "axbxc",
        "1x2x3x4",
        "",
        "1000x1000x1000",
        "1x4294967296x1",
    ] {
        assert!(parse_resolution(bad).is_err(), "{bad}");
    }
}
