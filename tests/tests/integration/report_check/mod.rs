//! Checks shared by the run tests: a results folder's report exists in both formats, every link
//! and picture in it resolves to a file in the folder, every export is linked, and the report's
//! paper-style table holds the run's own number.

use std::collections::BTreeSet;
use std::path::Path;

/// The relative targets of Markdown links and pictures, written `](<path>)` by the report.
fn markdown_targets(md: &str) -> Vec<String> {
    md.split("](<")
        .skip(1)
        .filter_map(|rest| rest.split_once(">)").map(|(path, _)| path.to_string()))
        .collect()
}

/// The values of `href="…"` and `src="…"` attributes.
fn html_targets(html: &str) -> Vec<String> {
    ["href=\"", "src=\""]
        .iter()
        .flat_map(|attr| {
            html.split(attr)
                .skip(1)
                .filter_map(|rest| rest.split_once('"').map(|(path, _)| path.to_string()))
        })
        .collect()
}

fn files_under(dir: &Path, prefix: &str, out: &mut BTreeSet<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let entry = entry.unwrap();
        let name = format!("{prefix}{}", entry.file_name().to_string_lossy());
        if entry.file_type().unwrap().is_dir() {
            files_under(&entry.path(), &format!("{name}/"), out);
        } else {
            out.insert(name);
        }
    }
}

/// Asserts the report of `run_dir` is complete and its table row named `row_label` shows
/// `expected_cell` (the run's number as the report formats it). Returns the Markdown.
pub fn check_report(run_dir: &Path, row_label: &str, expected_cell: &str) -> String {
    let md = std::fs::read_to_string(run_dir.join("report.md")).expect("report.md");
    let html = std::fs::read_to_string(run_dir.join("report.html")).expect("report.html");
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));

    let md_links = markdown_targets(&md);
    let html_links = html_targets(&html);
    assert!(md_links.len() >= 10, "too few links: {md_links:?}");
    for link in md_links.iter().chain(&html_links) {
        assert!(
            !link.starts_with('/') && !link.contains("..") && !link.contains("://"),
            "{link} is not a path inside the results folder"
        );
        assert!(run_dir.join(link).is_file(), "{link} does not resolve");
    }
    // Both formats refer to the same files, and every picture format the run wrote is shown.
    let md_set: BTreeSet<&String> = md_links.iter().collect();
    let html_set: BTreeSet<&String> = html_links.iter().collect();
    assert_eq!(md_set, html_set);
    let mut exports = BTreeSet::new();
    files_under(&run_dir.join("exports"), "exports/", &mut exports);
    // A slice stack has a PNG per printed layer (hundreds): the report links its manifest and its
    // first slice, and every slice must be one the manifest counts.
    let slices: Vec<&String> = exports
        .iter()
        .filter(|e| e.starts_with("exports/slices/slice-"))
        .collect();
    if !slices.is_empty() {
        let manifest = "exports/slices/manifest.json".to_string();
        assert!(
            md_set.contains(&manifest),
            "the slice manifest is not linked"
        );
        assert!(md_set.contains(slices[0]), "{} is not linked", slices[0]);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run_dir.join(&manifest)).unwrap())
                .unwrap();
        assert_eq!(json["layers"].as_u64(), Some(slices.len() as u64));
    }
    for export in exports.iter().filter(|e| !slices.contains(e)) {
        assert!(md_set.contains(export), "{export} is not linked");
    }
    for plot in ["progress_evaluations.png", "progress_wall_time.png"] {
        assert!(md.contains(&format!("](<{plot}>)")), "{plot} not shown");
    }

    // The table row carries the run's number, in both formats.
    let row = md
        .lines()
        .find(|l| l.starts_with(&format!("| {row_label} |")))
        .unwrap_or_else(|| panic!("no table row {row_label} in\n{md}"));
    let cells: Vec<&str> = row.trim_matches('|').split(" | ").map(str::trim).collect();
    assert!(
        cells.contains(&expected_cell),
        "{row} lacks {expected_cell}"
    );
    assert!(html.contains(&format!("<td>{expected_cell}</td>")));

    // The configuration as run is quoted whole.
    let config = std::fs::read_to_string(run_dir.join("config.toml")).unwrap();
    assert!(md.contains(config.trim_end()));
    md
}
