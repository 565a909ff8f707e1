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
mod tests;
