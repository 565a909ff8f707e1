use super::*;

#[test]
fn sizes_parse_with_binary_suffixes_and_refuse_nonsense() {
    assert_eq!(parse_size("8G"), Ok(8 << 30));
    assert_eq!(parse_size("512m"), Ok(512 << 20));
    assert_eq!(parse_size("1000"), Ok(1000));
    for bad in ["", "0", "-1G", "1.5G", "8X", "G", "99999999999T"] {
        assert!(parse_size(bad).is_err(), "{bad}");
    }
}

/// A task too large for the memory budget is refused before it starts, rather than making
/// the worker try to allocate (13.3 GB for a 1024x1024x8 beam) and abort. The estimate grows
/// with the voxel count and refuses it under a budget smaller than what it would ask for,
/// while the paper's beam passes a small one.
#[test]
fn an_evaluation_over_budget_is_refused_before_it_starts() {
    let beam: Scene = toml::from_str("kind = \"beam\"\ntarget = \"straight\"").unwrap();
    let huge = GridDims::new(1024, 1024, 8);
    assert!(
        estimate(&beam, huge) > 13_300_000_000,
        "at least what it really asked"
    );
    let err = check(&beam, huge, 8 << 30).unwrap_err();
    assert_eq!((err.dims, err.budget), (huge, 8 << 30));
    assert!(err.need > err.budget);
    let text = err.to_string();
    assert!(
        text.contains("1024x1024x8") && text.contains("budget"),
        "{text}"
    );
    assert!(check(&beam, GridDims::new(12, 40, 12), 256 << 20).is_ok());
    assert_eq!(
        estimate(&beam, GridDims::new(usize::MAX, usize::MAX, 2)),
        u64::MAX,
        "saturates, never wraps"
    );
}
