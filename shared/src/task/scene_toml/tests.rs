use super::*;

const BEAM: &str = "kind = \"beam\"\ntarget = \"circular_arc\"\n";

#[test]
fn a_bad_key_in_a_bare_scene_table_is_named_at_its_line() {
    let text = "kind = \"locomotion\"\n\n[dynamics]\nlink_precision = \"single\"\n";
    let error = scene_from_toml(text, SceneAt::Document).unwrap_err();
    assert!(
        error.starts_with("line 4: `link_precision = \"single\"`: unknown variant"),
        "{error}"
    );
}

#[test]
fn a_bad_key_in_a_configs_scene_is_named_at_its_line() {
    let text = format!("name = \"x\"\n[scene]\n{BEAM}lenght = 3\n");
    let error = scene_from_toml(&text, SceneAt::Config).unwrap_err();
    assert!(
        error.starts_with("line 5: `lenght = 3`: unknown field `lenght`"),
        "{error}"
    );
}

#[test]
fn a_scene_with_no_kind_is_refused_where_it_stands() {
    let error = scene_from_toml("target = \"straight\"\n", SceneAt::Document).unwrap_err();
    assert!(error.starts_with("line 1: "), "{error}");
    assert!(error.contains("kind"), "{error}");
}

#[test]
fn a_good_scene_reads_the_same_either_way() {
    let bare = scene_from_toml(BEAM, SceneAt::Document).unwrap();
    let in_config =
        scene_from_toml(&format!("seed = 1\n[scene]\n{BEAM}"), SceneAt::Config).unwrap();
    assert_eq!(bare.kind(), "beam");
    assert_eq!(
        serde_json::to_string(&bare).unwrap(),
        serde_json::to_string(&in_config).unwrap()
    );
}
