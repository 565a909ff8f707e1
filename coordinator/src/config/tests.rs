//! The run configuration read back and refused: defaults, and every bad key named in one line.

use super::*;

const MINIMAL: &str = r#"
name = "t"
[budget]
evaluations = 100
[resolution]
levels = [[6, 20, 6]]
[scene]
kind = "beam"
target = "straight"
"#;

/// A beam gets the climb unless it names a preset; a robot gets the paper's search; a key the
/// config writes wins over its preset.
#[test]
fn a_minimal_config_gets_its_tasks_preset() {
    let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
    let s = &c.search;
    assert_eq!(s.preset, Preset::Climb);
    assert_eq!((s.population, s.children_per_epoch), (48, 48));
    assert!(s.skip_unchanged && s.local_search.shared && s.local_search.combine);
    assert_eq!(s.local_search.fraction, 0.5);
    assert_eq!(s.local_search.finest_fraction, Some(1.0));
    assert!(c.resolution.stall_on_finest);
    assert_eq!(s.mutation.probability, 0.2);

    let paper = MINIMAL.replace("[budget]", "[search]\npreset = \"paper\"\n[budget]");
    let c = RunConfig::parse(&paper, Path::new("t.toml")).unwrap();
    let s = &c.search;
    assert_eq!((s.population, s.children_per_epoch), (50, 50));
    assert!(!s.skip_unchanged && !c.resolution.stall_on_finest);
    assert_eq!(s.local_search, crate::search::LocalSearchParams::default());

    let robot = "name = \"t\"\n[budget]\nevaluations = 100\n[resolution]\nlevels = [[6, 6, 6]]\n\
                 [scene]\nkind = \"locomotion\"\n";
    let c = RunConfig::parse(robot, Path::new("t.toml")).unwrap();
    assert_eq!(c.search.preset, Preset::Paper);

    let written = MINIMAL.replace("[budget]", "[search]\npopulation = 20\n[budget]");
    let c = RunConfig::parse(&written, Path::new("t.toml")).unwrap();
    assert_eq!((c.search.population, c.search.children_per_epoch), (20, 48));
}

/// The config a run records (its `config.toml`, its store) reads back to the same config: the
/// preset's values are written out, so a later change of a preset cannot change a recorded run.
#[test]
fn a_recorded_config_reads_back_to_itself() {
    let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
    let text = toml::to_string(&c.to_raw()).unwrap();
    assert!(text.contains("preset = \"climb\""), "{text}");
    let back = RunConfig::parse(&text, Path::new("t.toml")).unwrap();
    assert_eq!(back.to_raw(), c.to_raw());
}

/// `--set` takes the file's keys with the file's validation, applied in order; a bad value or
/// an unknown key is one line naming the `--set`.
#[test]
fn overrides_act_as_the_files_keys_and_a_bad_one_is_named() {
    let set = |s: &[&str]| -> Vec<Override> { s.iter().map(|s| s.parse().unwrap()).collect() };
    let c = RunConfig::parse_with(
        MINIMAL,
        Path::new("t.toml"),
        &set(&[
            "scene.target=polynomial4",
            "search.preset=paper",
            "budget.evaluations=200",
            "budget.evaluations=300",
        ]),
    )
    .unwrap();
    assert_eq!(c.search.preset, Preset::Paper);
    assert_eq!(c.budget.evaluations, Some(300), "the last one wins");
    assert!(
        toml::to_string(&c.to_raw())
            .unwrap()
            .contains("polynomial4")
    );
    for (bad, named) in [
        (
            "search.local_search.fraction=2",
            "search.local_search.fraction",
        ),
        ("search.populaton=3", "populaton"),
        ("budget.evaluations=many", "--set budget.evaluations=many"),
        ("name.x=1", "--set name.x=1: name is not a table"),
    ] {
        let err = RunConfig::parse_with(MINIMAL, Path::new("t.toml"), &set(&[bad]))
            .unwrap_err()
            .to_string();
        assert!(err.contains(named), "{bad}: {err}");
        assert!(!err.contains('\n'), "{err}");
    }
}

/// The quickstart compiled into the coordinator is a valid beam config on the climb.
#[test]
fn the_embedded_quickstart_is_valid() {
    let c = RunConfig::quickstart(&[]).unwrap();
    assert_eq!(c.search.preset, Preset::Climb);
    assert!(c.budget.target_rms_percent.is_some());
}

#[test]
fn an_unknown_key_is_one_line_naming_it() {
    let text = MINIMAL.replace("[budget]", "[budget]\nevaluation = 3");
    let err = RunConfig::parse(&text, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("evaluation") && err.contains("line 4"),
        "{err}"
    );
    assert!(!err.contains('\n'), "{err}");
}

#[test]
fn an_invalid_value_names_the_key() {
    let text = MINIMAL.replace("evaluations = 100", "evaluations = 10");
    let err = RunConfig::parse(&text, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("budget.evaluations"), "{err}");
}

#[test]
fn an_unknown_target_is_named() {
    let text = MINIMAL.replace("\"straight\"", "\"wavy\"");
    let err = RunConfig::parse(&text, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("wavy"), "{err}");
}

/// A bad value inside `[scene]` is reported at its own line and key, not at the `[scene]` line
/// without its key, although serde reads the tagged scene through a buffer that forgets positions.
#[test]
fn a_bad_value_inside_the_scene_is_reported_at_its_own_line_and_key() {
    let locomotion = "name = \"t\"\n[budget]\nevaluations = 100\n[resolution]\n\
                      levels = [[6, 6, 6]]\n[scene]\nkind = \"locomotion\"\n\
                      actuation_cycles = 4\n[scene.dynamics]\nlink_precision = \"mixed\"\n";
    RunConfig::parse(locomotion, Path::new("t.toml")).unwrap();
    // (text, its bad line, the key named, words of serde's message)
    let cases = [
        (
            locomotion.replace("\"mixed\"", "\"single\""),
            10,
            "link_precision",
            "unknown variant `single`",
        ),
        (
            locomotion.replace("actuation_cycles = 4", "actuation_cycles = \"four\""),
            8,
            "actuation_cycles",
            "invalid type",
        ),
        (
            locomotion.replace("\"mixed\"\n", "\"mixed\"\nvoxel_sise = 1.0\n"),
            11,
            "voxel_sise",
            "unknown field",
        ),
        (
            MINIMAL.replace(
                "target = \"straight\"",
                "target = \"straight\"\nload = \"heavy\"",
            ),
            10,
            "load",
            "",
        ),
    ];
    for (text, line, key, words) in cases {
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(&format!("config t.toml, line {line}: `{key}")),
            "{err}"
        );
        assert!(err.contains(words) && !err.contains('\n'), "{err}");
    }
    // An error outside the scene keeps its own place while the scene is sound.
    let err = RunConfig::parse(
        &locomotion.replace("evaluations = 100", "evaluations = \"many\""),
        Path::new("t.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.starts_with("config t.toml, line 3: `evaluations"),
        "{err}"
    );
}

/// Sizes that would overflow, or that no machine could hold, are refused by validation with the
/// key named on one line, instead of passing it and panicking or aborting later.
#[test]
fn sizes_that_would_overflow_are_refused_naming_their_key() {
    let cases = [
        (
            "levels = [[6, 20, 6]]",
            "levels = [[1, 4294967296, 4294967296]]",
            "resolution.levels[0]",
        ),
        (
            "levels = [[6, 20, 6]]",
            "levels = [[2097152, 4194304, 2097152]]",
            "resolution.levels[0]",
        ),
        (
            "[budget]",
            "[search]\npopulation = 4611686018427387904\nislands = 4\n[budget]",
            "search.population",
        ),
        (
            "[budget]",
            "[search]\npopulation = 1099511627776\n[budget]",
            "search.population",
        ),
        (
            "[budget]",
            "[search]\npopulation = 1000\nislands = 4096\n[budget]",
            "search.islands x search.population",
        ),
        (
            "[budget]",
            "[search]\nislands = 100000\n[budget]",
            "search.islands",
        ),
        (
            "[budget]",
            "[search]\nchildren_per_epoch = 4611686018427387904\n[budget]",
            "search.children_per_epoch",
        ),
        (
            "[budget]",
            "[cluster]\nlocal_workers = 100000\n[budget]",
            "cluster.local_workers",
        ),
        (
            "[budget]",
            "[cluster]\nlease_ms = 9223372036854775807\n[budget]",
            "cluster.lease_ms",
        ),
        // Beyond what TOML's integers hold (and so beyond what a run could record in its
        // config.toml): refused where it is written.
        (
            "[budget]",
            "[cluster]\nlease_ms = 18446744073709551615\n[budget]",
            "line 4: `lease_ms = 18446744073709551615`",
        ),
        (
            "name = \"t\"",
            "name = \"t\"\nseed = 18446744073709551615",
            "line 3: `seed = 18446744073709551615`",
        ),
    ];
    for (from, to, key) in cases {
        let text = MINIMAL.replace(from, to);
        let err = RunConfig::parse(&text, Path::new("t.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains(key), "{to}: {err}");
        assert!(!err.contains('\n'), "{err}");
    }
}

#[test]
fn a_bad_local_search_key_is_named() {
    let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
    assert!(c.search.migration.only_if_fitter);
    let text = MINIMAL.replace(
        "[budget]",
        "[search.local_search]\nfraction = 2.0\n[budget]",
    );
    let err = RunConfig::parse(&text, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("search.local_search.fraction"), "{err}");
}
