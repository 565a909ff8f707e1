use super::*;

#[test]
fn a_written_key_wins_and_a_missing_one_comes_from_the_preset() {
    let mut config: toml::Table = "[search]\npopulation = 20\n[search.local_search]\nstep = 0.1"
        .parse()
        .unwrap();
    lay_under(&mut config, Preset::Climb.defaults());
    let search = config["search"].as_table().unwrap();
    assert_eq!(search["population"].as_integer(), Some(20));
    assert_eq!(search["children_per_epoch"].as_integer(), Some(48));
    let local = search["local_search"].as_table().unwrap();
    assert_eq!(local["step"].as_float(), Some(0.1));
    assert_eq!(local["fraction"].as_float(), Some(0.5));
    assert_eq!(
        config["resolution"]["stall_on_finest"].as_bool(),
        Some(true)
    );
}

#[test]
fn each_preset_names_itself() {
    for preset in [Preset::Climb, Preset::Paper] {
        let table = preset.defaults();
        assert_eq!(table["search"]["preset"].as_str(), Some(preset.key()));
    }
}
