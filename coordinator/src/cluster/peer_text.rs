//! Text a peer sent (a worker's name, its error message, an id it made up) made safe to repeat:
//! control characters are escaped, so a name holding a newline or an ANSI sequence cannot forge a
//! log line or repaint a terminal, and the length is capped, so a megabyte id is not echoed back
//! in every error. Everything from the network passes through here before a log, an error or the
//! run store sees it.

/// Longest worker name kept, in characters.
pub const MAX_NAME_CHARS: usize = 128;
/// Longest worker error message kept, in characters.
pub const MAX_ERROR_CHARS: usize = 2000;
/// Longest id or other short field repeated in an error, in characters.
pub const MAX_ID_CHARS: usize = 80;

/// `text` with every control character (C0, DEL, C1; including `\n`, `\r`, `ESC`) and the
/// Unicode line and paragraph separators written as escapes, cut after `max` characters of the
/// original with `…` and the total length appended.
pub fn clean(text: &str, max: usize) -> String {
    let mut out = String::with_capacity(text.len().min(max * 2));
    for (taken, c) in text.chars().enumerate() {
        if taken == max {
            out.push_str(&format!("… ({} chars)", text.chars().count()));
            return out;
        }
        if c.is_control()
            || matches!(
                c,
                '\u{2028}' | '\u{2029}' | '\u{202e}' | '\u{2066}'..='\u{2069}'
            )
        {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
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
}
