//! Every `coordinator` command the README and the docs show still works: each one, run from the
//! repository root with `--check` added, reads and validates its config, `--set`s and preset.
//! A renamed key, flag or config file in the docs fails here instead of in a user's terminal.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The Markdown files a user reads: the README and everything under docs/.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut folders = vec![root().join("docs")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages.sort();
    pages
}

/// The shell commands of a page's fenced `sh` blocks, backslash-continued lines joined and
/// trailing comments dropped.
fn shell_commands(text: &str) -> Vec<String> {
    let (mut commands, mut in_block, mut current) = (Vec::new(), false, String::new());
    for line in text.lines() {
        let trimmed = line.trim();
        if trimmed.starts_with("```") {
            in_block = !in_block && (trimmed == "```sh" || trimmed == "```bash");
            continue;
        }
        if !in_block {
            continue;
        }
        let code = match trimmed.find(" #") {
            Some(i) => trimmed[..i].trim_end(),
            None => trimmed,
        };
        if code.starts_with('#') {
            continue;
        }
        match code.strip_suffix('\\') {
            Some(part) => current.push_str(part),
            None => {
                current.push_str(code);
                commands.push(std::mem::take(&mut current).trim().to_owned());
            }
        }
    }
    commands
}

/// Splits a command line as a shell would for the plain words, 'single' and "double" quotes the
/// docs use.
fn words(command: &str) -> Vec<String> {
    let (mut words, mut word, mut quote, mut started) = (Vec::new(), String::new(), None, false);
    for c in command.chars() {
        match (quote, c) {
            (None, '\'' | '"') => {
                quote = Some(c);
                started = true;
            }
            (Some(q), c) if c == q => quote = None,
            (None, c) if c.is_whitespace() => {
                if started {
                    words.push(std::mem::take(&mut word));
                    started = false;
                }
            }
            (_, c) => {
                word.push(c);
                started = true;
            }
        }
    }
    if started {
        words.push(word);
    }
    words
}

#[test]
fn every_documented_coordinator_command_checks() {
    let scratch = std::env::temp_dir().join(format!("amorph-doc-commands-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).unwrap();
    let mut checked = 0;
    let mut failed = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for command in shell_commands(&text) {
            let words = words(&command);
            let Some(at) = words.windows(4).position(|w| {
                w == ["cargo", "run", "--release", "--bin"] || w[..3] == ["cargo", "run", "--bin"]
            }) else {
                continue;
            };
            let rest = &words[at..];
            let bin = rest.iter().position(|w| w == "--bin").map(|i| &rest[i + 1]);
            if bin.is_none_or(|b| b != "coordinator") {
                continue;
            }
            let args: Vec<&String> = match rest.iter().position(|w| w == "--") {
                Some(i) => rest[i + 1..].iter().collect(),
                None => Vec::new(),
            };
            // `credentials` commands write files, so they run for real in a folder of their own;
            // every other command only checks its config.
            let out = if args.first().is_some_and(|a| *a == "credentials") {
                Command::new(env!("CARGO_BIN_EXE_coordinator"))
                    .args(&args)
                    .current_dir(&scratch)
                    .output()
                    .unwrap()
            } else {
                Command::new(env!("CARGO_BIN_EXE_coordinator"))
                    .args(&args)
                    .arg("--check")
                    .current_dir(root())
                    .env("AMORPH_TOKEN", "documentation")
                    .output()
                    .unwrap()
            };
            checked += 1;
            if !out.status.success() {
                failed.push(format!(
                    "{}: `{command}`: {}",
                    page.strip_prefix(root()).unwrap_or(&page).display(),
                    String::from_utf8_lossy(&out.stderr).trim()
                ));
            }
        }
    }
    assert!(
        checked >= 10,
        "only {checked} coordinator commands found in the docs"
    );
    assert!(failed.is_empty(), "{failed:#?}");
}

#[test]
fn the_shell_reader_joins_continued_lines_and_honours_quotes() {
    let text = "```sh\ncargo run -- --set a=1 \\\n    --set 'b=[1, 2]'   # note\n```\n";
    assert_eq!(
        shell_commands(text),
        ["cargo run -- --set a=1 --set 'b=[1, 2]'"]
    );
    assert_eq!(
        words("x --set 'b=[1, 2]' \"c d\""),
        ["x", "--set", "b=[1, 2]", "c d"]
    );
}
