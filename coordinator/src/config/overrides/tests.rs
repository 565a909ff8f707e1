use super::*;

#[test]
fn values_are_toml_and_bare_words_are_strings() {
    let set = |s: &str| s.parse::<Override>().unwrap().value;
    assert_eq!(set("a=0.5"), toml::Value::Float(0.5));
    assert_eq!(set("a=3"), toml::Value::Integer(3));
    assert_eq!(set("a = true"), toml::Value::Boolean(true));
    assert_eq!(
        set("a=polynomial4"),
        toml::Value::String("polynomial4".into())
    );
    assert_eq!(set("a=\"ring\""), toml::Value::String("ring".into()));
    assert_eq!(
        set("a=[6000]"),
        toml::Value::Array(vec![toml::Value::Integer(6000)])
    );
}

#[test]
fn a_path_creates_its_tables_and_refuses_to_run_through_a_value() {
    let mut doc: toml::Table = "name = \"x\"".parse().unwrap();
    let set: Override = "search.local_search.fraction=0.25".parse().unwrap();
    set.apply(&mut doc).unwrap();
    assert_eq!(
        doc["search"]["local_search"]["fraction"].as_float(),
        Some(0.25)
    );
    let through: Override = "name.part=1".parse().unwrap();
    let err = through.apply(&mut doc).unwrap_err();
    assert_eq!(err, "--set name.part=1: name is not a table");
    assert!("nokey".parse::<Override>().is_err());
    assert!("a..b=1".parse::<Override>().is_err());
}
