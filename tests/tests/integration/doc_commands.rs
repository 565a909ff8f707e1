//! Every `coordinator` and `worker` command the README and the docs show still works. A
//! coordinator command, run from the repository root with `--check` added, reads and validates its
//! config, `--set`s and preset (a `credentials` command runs for real, in a folder of its own); a
//! `worker export` or `worker evaluate` command runs as written on a finished run of the name it
//! reads. A renamed key, flag or config file in the docs fails here instead of in a user's
//! terminal.

use std::path::PathBuf;
use std::process::Command;

use amorph_tests::{
    binary, files_under, repository_root as root, run_locally, scratch_dir, test_config,
};

/// A documented `cargo run [--release] --bin NAME -- ARGS` command: the binary's name and its
/// arguments.
struct CargoRun {
    page: PathBuf,
    command: String,
    bin: String,
    args: Vec<String>,
}

/// Every `cargo run` command in the fenced shell blocks of the README and docs/.
fn documented_runs() -> Vec<CargoRun> {
    let mut runs = Vec::new();
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
            let Some(bin) = rest
                .iter()
                .position(|w| w == "--bin")
                .map(|i| rest[i + 1].clone())
            else {
                continue;
            };
            let args = match rest.iter().position(|w| w == "--") {
                Some(i) => rest[i + 1..].to_vec(),
                None => Vec::new(),
            };
            runs.push(CargoRun {
                page: page.clone(),
                command: command.clone(),
                bin,
                args,
            });
        }
    }
    runs
}

impl CargoRun {
    fn failure(&self, out: &std::process::Output) -> Option<String> {
        (!out.status.success()).then(|| {
            format!(
                "{}: `{}`: {}",
                self.page
                    .strip_prefix(root())
                    .unwrap_or(&self.page)
                    .display(),
                self.command,
                String::from_utf8_lossy(&out.stderr).trim()
            )
        })
    }
}

/// The Markdown files a user reads: the README and everything under docs/.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    pages.extend(files_under(&root().join("docs"), &["md"]));
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
    let scratch = scratch_dir("doc-credentials");
    let mut checked = 0;
    let mut failed = Vec::new();
    let commands = documented_runs();
    let coordinator = commands.iter().filter(|r| r.bin == "coordinator");
    // `dashboard` serves a store until stopped: its own test below runs it.
    for run in coordinator.filter(|r| r.args.first().is_none_or(|a| a != "dashboard")) {
        // `credentials` commands write files, so they run for real in a folder of their own;
        // every other command only checks its config.
        let out = if run.args.first().is_some_and(|a| a == "credentials") {
            Command::new(binary("coordinator"))
                .args(&run.args)
                .current_dir(&scratch)
                .output()
                .unwrap()
        } else {
            Command::new(binary("coordinator"))
                .args(&run.args)
                .arg("--check")
                .current_dir(root())
                .env("AMORPH_TOKEN", "documentation")
                .output()
                .unwrap()
        };
        checked += 1;
        failed.extend(run.failure(&out));
    }
    assert!(
        checked >= 10,
        "only {checked} coordinator commands found in the docs"
    );
    assert!(failed.is_empty(), "{failed:#?}");
}

/// `worker export` and `worker evaluate` as the docs write them, in a folder holding a finished
/// run (a small beam, 40 evaluations at 4x12x4) under each `results/<name>/` they read.
#[test]
fn every_documented_worker_export_and_evaluate_runs() {
    let scratch = scratch_dir("doc-worker");
    let runs: Vec<CargoRun> = documented_runs()
        .into_iter()
        .filter(|r| {
            r.bin == "worker"
                && r.args
                    .first()
                    .is_some_and(|a| a == "export" || a == "evaluate")
        })
        .collect();
    let mut names: Vec<String> = (runs.iter())
        .flat_map(|r| r.args.iter())
        .filter_map(|a| {
            a.strip_prefix("results/")?
                .split('/')
                .next()
                .map(str::to_owned)
        })
        .collect();
    names.sort();
    names.dedup();
    for name in &names {
        let config = test_config(
            "small_beam",
            &scratch.join("results"),
            &[&format!("name={name}"), "budget.evaluations=40"],
        );
        run_locally(&config, 2);
    }
    let mut failed = Vec::new();
    for run in &runs {
        let out = Command::new(binary("worker"))
            .args(&run.args)
            .current_dir(&scratch)
            .output()
            .unwrap();
        failed.extend(run.failure(&out));
    }
    assert!(
        runs.len() >= 2 && !names.is_empty(),
        "only {} worker export/evaluate commands found in the docs",
        runs.len()
    );
    assert!(failed.is_empty(), "{failed:#?}");
}

/// `coordinator dashboard results/NAME/run.sqlite` as the docs write it (on a free port), on a
/// finished run: it serves the run's status.
#[test]
fn every_documented_dashboard_command_serves_its_store() {
    let scratch = scratch_dir("doc-dashboard");
    let runs: Vec<CargoRun> = documented_runs()
        .into_iter()
        .filter(|r| r.bin == "coordinator" && r.args.first().is_some_and(|a| a == "dashboard"))
        .collect();
    assert!(
        !runs.is_empty(),
        "no coordinator dashboard command found in the docs"
    );
    for run in &runs {
        let store = run.args.get(1).expect("dashboard STORE");
        let name = (store.strip_prefix("results/"))
            .and_then(|rest| rest.strip_suffix("/run.sqlite"))
            .unwrap_or_else(|| panic!("`{}`: not a results/NAME/run.sqlite", run.command));
        let config = test_config(
            "small_beam",
            &scratch.join("results"),
            &[&format!("name={name}"), "budget.evaluations=40"],
        );
        if !amorph_coordinator::store::RunStore::path_for(&config).exists() {
            run_locally(&config, 2);
        }
        let mut args = run.args.clone();
        match args.iter().position(|a| a == "--listen") {
            Some(i) => args[i + 1] = "127.0.0.1:0".into(),
            None => args.extend(["--listen".into(), "127.0.0.1:0".into()]),
        }
        let mut child = KilledOnDrop(
            Command::new(binary("coordinator"))
                .args(&args)
                .current_dir(&scratch)
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap(),
        );
        let stderr = std::io::BufReader::new(child.0.stderr.take().unwrap());
        let url = std::io::BufRead::lines(stderr)
            .map_while(Result::ok)
            .find_map(|line| {
                Some(
                    line.split(" on http://")
                        .nth(1)?
                        .split('/')
                        .next()?
                        .to_owned(),
                )
            });
        let served = url
            .and_then(|addr| addr.parse().ok())
            .map(|addr| amorph_tests::http::get(addr, "/api/status", &[]));
        drop(child);
        let (code, _, body) = served.unwrap_or_else(|| panic!("`{}` never served", run.command));
        assert_eq!(code, 200, "`{}`", run.command);
        let status: serde_json::Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(status["run"]["name"], name, "`{}`", run.command);
    }
}

/// A child process that is killed when dropped, so a failing assertion leaves none behind.
struct KilledOnDrop(std::process::Child);

impl Drop for KilledOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
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
