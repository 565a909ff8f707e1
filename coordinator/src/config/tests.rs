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

#[test]
fn a_minimal_config_is_accepted_with_paper_defaults() {
    let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
    assert_eq!(c.raw.search.population, 50);
    assert_eq!(c.raw.search.mutation.probability, 0.2);
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

/// A bad value inside `[scene]` used to be reported at the `[scene]` line without its key:
/// serde reads the tagged scene through a buffer that forgets positions.
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

/// Issue 12, item 4: sizes that overflowed passed validation, then panicked or aborted.
#[test]
fn regression_config_sizes_that_overflow_name_their_key() {
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
            "[search]\nsplit_after_stall = 5\n[budget]",
            "search.split_after_stall = 5 needs search.islands",
        ),
        (
            "levels = [[6, 20, 6]]",
            "levels = [[6, 20, 6]]\nmerge_islands = true\n[search]\nislands = 2\npopulation = 4\nsplit_after_stall = 5",
            "search.split_after_stall = 5 and resolution.merge_islands",
        ),
        (
            "[budget]",
            "[cluster]\nlocal_workers = 100000\n[budget]",
            "cluster.local_workers",
        ),
        (
            "[budget]",
            "[cluster]\nlease_ms = 18446744073709551615\n[budget]",
            "cluster.lease_ms",
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
fn the_search_variation_keys_default_off_and_a_bad_one_is_named() {
    let c = RunConfig::parse(MINIMAL, Path::new("t.toml")).unwrap();
    assert_eq!(
        c.raw.search.variation(),
        crate::search::Variation::default()
    );
    assert_eq!(c.raw.search.local_search.fraction, 0.0);
    assert!(c.raw.search.migration.only_if_fitter);
    let text = MINIMAL.replace(
        "[budget]",
        "[search.local_search]\nfraction = 2.0\n[budget]",
    );
    let err = RunConfig::parse(&text, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("search.local_search.fraction"), "{err}");
}

/// The residual model (its pick or its least-squares step) needs a task whose fitness is a sum of
/// squared residuals: a beam takes the key, a robot's config is refused with the key, its value
/// and the scene's kind named.
#[test]
fn combining_by_residuals_needs_a_least_squares_task() {
    for by in ["residuals", "least_squares"] {
        let keys = format!(
            "[search.local_search]\nfraction = 0.5\ncombine = true\ncombine_by = \"{by}\"\n"
        );
        assert_beam_only(&keys, "search.local_search.combine_by", by);
    }
}

/// `keys` (a `[search.local_search]` table) are taken in a beam's config, and a robot's config
/// with them is refused naming `key`, its `value` and the scene's kind.
fn assert_beam_only(keys: &str, key: &str, value: &str) {
    let beam = MINIMAL.replace("[budget]", &format!("{keys}[budget]"));
    RunConfig::parse(&beam, Path::new("t.toml")).unwrap();
    let robot = format!(
        "name = \"t\"\n{keys}[budget]\nevaluations = 100\n[resolution]\nlevels = [[6, 6, 6]]\n\
         [scene]\nkind = \"locomotion\"\n"
    );
    let err = RunConfig::parse(&robot, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(key) && err.contains(value) && err.contains("locomotion"),
        "{err}"
    );
}

/// Insertions drawn by a flip model need a task that has one and insertions to draw: a beam takes
/// the key, a robot's config is refused naming the key, its value and the scene's kind, and the
/// key without `insertion` is refused naming both keys.
#[test]
fn insertions_by_a_flip_model_need_a_model_and_insertions() {
    let keys =
        "[search.local_search]\nfraction = 0.5\ninsertion = 0.5\ninsertion_by = \"flip_model\"\n";
    assert_beam_only(keys, "search.local_search.insertion_by", "flip_model");
    let without = MINIMAL.replace(
        "[budget]",
        "[search.local_search]\nfraction = 0.5\ninsertion_by = \"flip_model\"\n[budget]",
    );
    let err = RunConfig::parse(&without, Path::new("t.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("insertion_by") && err.contains("search.local_search.insertion > 0"),
        "{err}"
    );
}
