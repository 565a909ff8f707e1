use super::*;

#[test]
fn control_characters_are_escaped_so_no_line_can_be_forged() {
    let forged = "honest\n2026-11-23T12:00:00Z  WARN worker went silent\u{1b}[2J\r\u{85}";
    let cleaned = clean(forged, 1000);
    assert!(!cleaned.chars().any(char::is_control), "{cleaned}");
    assert!(cleaned.starts_with("honest\\n2026"));
    assert!(cleaned.contains("\\u{1b}[2J\\r\\u{85}"));
    // Plain text, including non-ASCII names, is kept as written.
    assert_eq!(clean("gpu-node-7 (Zürich)", 1000), "gpu-node-7 (Zürich)");
}

#[test]
fn long_text_is_capped_on_a_character_boundary_and_says_how_long_it_was() {
    let long = "é".repeat(1 << 20);
    let cleaned = clean(&long, 10);
    assert_eq!(cleaned, format!("{}… (1048576 chars)", "é".repeat(10)));
    assert_eq!(clean("short", 5), "short");
}
