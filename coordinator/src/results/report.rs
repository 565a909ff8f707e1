//! The run report (report.md and report.html): what ran, the task's paper-style table, the
//! pictures, links to every file, and the configuration. Only files that exist are linked, so
//! every link resolves.

use std::path::{Path, PathBuf};

use amorph::report::{Block, Link, Picture, Report};
use amorph::task::{Artefact, Scene};

use super::finishing::FinerCheck;
use crate::ids::TaskId;
use crate::search::Front;
use crate::summary::{RunSummary, StopReason};

/// What the report shows besides the summary: files written by the results writer.
pub(super) struct ReportInputs<'a> {
    pub dir: &'a Path,
    pub name: &'a str,
    pub scene: &'a Scene,
    pub exports: &'a [PathBuf],
    pub island_pictures: &'a [String],
    pub artefacts: &'a [Artefact],
    pub finer: Option<&'a FinerCheck>,
    pub config_text: &'a str,
}

pub(super) fn run_report(summary: &RunSummary, inputs: &ReportInputs<'_>) -> Report {
    let best = summary.best();
    let exists = |name: &str| inputs.dir.join(name).is_file();
    let picture = |path: &str, caption: &str| Picture {
        path: path.into(),
        caption: caption.into(),
    };
    let mut report = Report::new(format!("Amorph run {}", inputs.name));
    report.push(Block::Paragraph(format!(
        "Stopped by the {} after {} epochs, {} evaluations and {:.1} s of wall time; final resolution {}; best fitness {}.",
        words(&format!("{:?}", summary.stop)),
        summary.epochs,
        summary.evaluations,
        summary.wall_seconds,
        summary.dims,
        best.outcome
            .fitness()
            .map_or("none (no design evaluated)".to_string(), |f| format!("{f:e}")),
    )));
    if summary.stop == StopReason::Shutdown {
        report.push(Block::Paragraph(
            "The run was stopped before its end and continues with `--resume`; the end-of-run work (the check at twice the resolution, the print slices and the task's own pictures) is done when it finishes.".into(),
        ));
    }
    let (heading, table) = inputs.scene.table(&best.outcome, summary.dims);
    report.push(Block::Heading(heading));
    report.push(table);
    if let Some(finer) = inputs.finer {
        report.push(Block::Heading("Twice as fine".into()));
        report.push(Block::Paragraph(finer.sentence()));
    }

    report.push(Block::Heading("Best design".into()));
    let mut pictures = vec![picture("exports/design.png", "best design, isometric view")];
    pictures.extend(
        inputs
            .artefacts
            .iter()
            .filter(|a| exists(&a.path))
            .filter_map(|a| Some(picture(&a.path, a.caption.as_deref()?))),
    );
    report.push(Block::Pictures(pictures));
    report.push(Block::Heading("Best design of each island".into()));
    report.push(Block::Pictures(
        inputs
            .island_pictures
            .iter()
            .enumerate()
            .map(|(i, p)| picture(p, &format!("island {i}")))
            .collect(),
    ));
    if let Some(front) = &summary.pareto {
        front_section(&mut report, front);
    }
    report.push(Block::Heading("Progress".into()));
    report.push(Block::Pictures(vec![
        picture(
            "progress_evaluations.png",
            "best of each island against evaluations",
        ),
        picture(
            "progress_wall_time.png",
            "best of each island against wall time",
        ),
    ]));

    report.push(Block::Heading("Fabrication files".into()));
    report.push(Block::Links(
        inputs
            .exports
            .iter()
            .map(|p| Link {
                label: export_label(p),
                path: format!("exports/{}", p.display()),
            })
            .collect(),
    ));
    report.push(Block::Heading("Run files".into()));
    let mut run_files: Vec<String> = [
        "config.toml",
        "history.csv",
        "best_genome.json",
        "population.json",
        "best_voxels.json",
        "summary.json",
        "summary.md",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    run_files.extend(
        inputs
            .artefacts
            .iter()
            .filter(|a| a.caption.is_none())
            .map(|a| a.path.clone()),
    );
    run_files.extend((0..summary.populations.len()).map(|i| format!("island-{i}-best.json")));
    report.push(Block::Links(
        run_files
            .into_iter()
            .filter(|f| exists(f))
            .map(|f| Link {
                label: f.clone(),
                path: f,
            })
            .collect(),
    ));
    report.push(Block::Heading("Configuration (as run)".into()));
    report.push(Block::Code {
        language: "toml".into(),
        text: inputs.config_text.to_string(),
    });
    report
}

/// summary.md: the task's table and one line on the run.
/// The trade-offs a multi-objective run found: the front's size and hypervolume, its picture, and
/// its designs along the first objective (twelve spread evenly over it, past twelve).
fn front_section(report: &mut Report, front: &Front) {
    report.push(Block::Heading("Trade-offs".into()));
    let names: Vec<&str> = front.objectives.iter().map(|o| o.name).collect();
    report.push(Block::Paragraph(format!(
        "{} designs on the Pareto front of {} at the final resolution (the designs the run evaluated there that no other beats in every objective), dominating a hypervolume of {:.3e} against the config's `hypervolume_reference`. `pareto.csv` lists them all; `worker export --run <this folder> --design ID` exports any of them.",
        front.members.len(),
        names.join(" against "),
        front.hypervolume
    )));
    report.push(Block::Pictures(vec![Picture {
        path: "pareto.png".into(),
        caption:
            "the front on its first two objectives, and the fittest design by the task's fitness"
                .into(),
    }]));
    let rows = front.along_first();
    let shown: Vec<&(TaskId, Vec<f64>)> = if rows.len() <= 12 {
        rows
    } else {
        (0..12).map(|k| rows[k * (rows.len() - 1) / 11]).collect()
    };
    let mut header = vec!["design (task_id)".to_string()];
    header.extend(front.objectives.iter().map(|o| {
        if o.unit.is_empty() {
            o.name.to_string()
        } else {
            format!("{} ({})", o.name, o.unit)
        }
    }));
    report.push(Block::Table {
        header,
        rows: (shown.iter())
            .map(|(task, values)| {
                let mut row = vec![task.0.to_string()];
                row.extend(values.iter().map(|v| format!("{v:.4}")));
                row
            })
            .collect(),
    });
}

pub(super) fn summary_markdown(summary: &RunSummary, name: &str, scene: &Scene) -> String {
    let (heading, table) = scene.table(&summary.best().outcome, summary.dims);
    let mut doc = Report::new(format!("Run `{name}`"));
    doc.push(Block::Heading(heading));
    doc.push(table);
    doc.push(Block::Paragraph(format!(
        "{} evaluations, {:.1} s of wall time, final resolution {}, stopped by the {}.",
        summary.evaluations,
        summary.wall_seconds,
        summary.dims,
        words(&format!("{:?}", summary.stop)),
    )));
    doc.to_markdown()
}

/// "EvaluationBudget" → "evaluation budget": a variant name as words for a sentence.
fn words(camel: &str) -> String {
    let mut out = String::new();
    for c in camel.chars() {
        if c.is_uppercase() && !out.is_empty() {
            out.push(' ');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// What a fabrication file is for, from its name.
fn export_label(path: &Path) -> String {
    let name = path.display().to_string();
    let in_slices = path.starts_with("slices");
    let what = match path.extension().and_then(|e| e.to_str()) {
        Some("png") if in_slices => "voxel-print slice, the first of the stack",
        Some("json") if in_slices => "voxel-print manifest: pitch, size, colours",
        Some("stl") => "binary STL, mm",
        Some("3mf") => "multi-material 3MF",
        Some("vxa") => "VoxCAD / Voxelyze",
        Some("svg") => "laser-cut layer",
        Some("png") => "render",
        Some("gif") => "animation",
        _ => "file",
    };
    format!("{name} ({what})")
}
