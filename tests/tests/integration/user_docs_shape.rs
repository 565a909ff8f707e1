//! The user's documents keep the shape the project promises: a README a newcomer reads in one
//! sitting and a manual rather than a notebook. The limits are the product's own (README at most
//! 150 lines, docs/ at most 3,000 in all), so a page that grows past them fails here. The configs'
//! headings are checked where every config is loaded (designer_goals.rs).

use std::path::Path;

use amorph_tests::{files_under, repository_root as root};

fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).unwrap().lines().count()
}

#[test]
fn the_readme_fits_in_150_lines() {
    let n = lines(&root().join("README.md"));
    assert!(n <= 150, "README.md has {n} lines; at most 150");
}

#[test]
fn the_manual_fits_in_3000_lines() {
    let pages = files_under(&root().join("docs"), &["md"]);
    let total: usize = pages.iter().map(|p| lines(p)).sum();
    assert!(!pages.is_empty());
    assert!(
        total <= 3000,
        "docs/ has {total} lines in {} pages; at most 3,000",
        pages.len()
    );
}

/// "session" followed by a number: the mark of a diary entry.
fn speaks_of_a_session(text: &str) -> bool {
    let lower = text.to_ascii_lowercase();
    lower.match_indices("session").any(|(at, word)| {
        let rest = lower[at + word.len()..].trim_start_matches(['s', ' ', '#']);
        rest.starts_with(|c: char| c.is_ascii_digit())
    })
}

#[test]
fn the_diary_check_recognises_a_session_number() {
    // Built at run time, so that this file does not trip the check below.
    assert!(speaks_of_a_session(&format!(
        "as measured in Session {}, the",
        12
    )));
    assert!(speaks_of_a_session(&format!("sessions {}-5", 3)));
    assert!(!speaks_of_a_session("a session secret of 32 bytes"));
    assert!(!speaks_of_a_session("the session ends"));
}

#[test]
fn no_document_config_or_source_numbers_sessions() {
    let mut files = Vec::new();
    for (dir, extensions) in [
        ("docs", &["md"][..]),
        ("configs", &["toml"]),
        ("deploy", &["md", "sh", "yml", "yaml"]),
        ("shared", &["rs", "md"]),
        ("coordinator", &["rs", "md", "js", "html"]),
        ("worker", &["rs", "md"]),
        ("proto", &["rs", "proto"]),
        ("tests", &["rs", "sh", "py"]),
        ("python", &["rs", "py", "md"]),
    ] {
        files.extend(files_under(&root().join(dir), extensions));
    }
    for top in ["README.md", "ARCHITECTURE.md", ".ci/run"] {
        files.push(root().join(top));
    }
    let offenders: Vec<String> = files
        .iter()
        .filter(|p| p.exists() && speaks_of_a_session(&std::fs::read_to_string(p).unwrap()))
        .map(|p| p.strip_prefix(root()).unwrap_or(p).display().to_string())
        .collect();
    assert!(offenders.is_empty(), "numbered sessions in {offenders:?}");
}
