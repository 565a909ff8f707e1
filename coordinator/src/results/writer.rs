use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use amorph::genome::Genome;
use amorph::task::{Outcome, Scene};
use amorph::voxel::{GridDims, VoxelGrid};
use serde::Serialize;

use super::finishing::FinerCheck;
use super::plots::write_progress;
use super::report::{ReportInputs, run_report, summary_markdown};
use crate::config::RunConfig;
use crate::search::{Front, Individual};
use crate::summary::{HistoryRow, RunSummary, StopReason, fittest};

/// Samples along the longest side for the smooth surface STL written at the end of a run: three
/// per voxel at the paper's 20×20×20 (measured: 1.4 MB per material for a 1,006-voxel robot,
/// written in 0.25 s).
const SMOOTH_SAMPLES_AT_END: usize = 60;

#[derive(Debug)]
pub struct ResultWriter {
    dir: PathBuf,
    history: BufWriter<File>,
    best_rank: f64,
    best_dims: Option<GridDims>,
    config: RunConfig,
    /// The configuration exactly as written to config.toml, for the report.
    config_text: String,
}

#[derive(Serialize)]
struct SavedIndividual<'a> {
    genome: &'a Genome,
    outcome: &'a Outcome,
}

impl ResultWriter {
    pub fn create(config: &RunConfig) -> std::io::Result<Self> {
        let dir = config.run_dir();
        std::fs::create_dir_all(&dir)?;
        let text = toml::to_string_pretty(&config.to_raw()).map_err(std::io::Error::other)?;
        std::fs::write(dir.join("config.toml"), &text)?;
        let mut history = BufWriter::new(File::create(dir.join("history.csv"))?);
        writeln!(
            history,
            "epoch,evaluations,wall_seconds,resolution,island,best_fitness,best_{},mean_fitness,replacements{}",
            config.scene.figure_spec().column,
            if config.search.objectives.is_empty() {
                ""
            } else {
                ",hypervolume"
            }
        )?;
        Ok(Self {
            dir,
            history,
            best_rank: f64::NEG_INFINITY,
            best_dims: None,
            config: config.clone(),
            config_text: text,
        })
    }

    pub fn dir(&self) -> &std::path::Path {
        &self.dir
    }

    pub fn history(&mut self, row: &HistoryRow) -> std::io::Result<()> {
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
        write!(
            self.history,
            "{},{},{:.3},{},{},{},{},{},{}",
            row.epoch,
            row.evaluations,
            row.wall_seconds,
            row.resolution,
            row.island,
            opt(row.best_fitness),
            opt(row.best_figure),
            opt(row.mean_fitness),
            row.replacements
        )?;
        if let Some(hypervolume) = row.hypervolume {
            write!(self.history, ",{hypervolume:e}")?;
        }
        writeln!(self.history)?;
        self.history.flush()
    }

    /// Saves the best design whenever the run's best improves (ranks are compared per resolution,
    /// so a resolution switch starts the comparison afresh).
    pub fn best_so_far(&mut self, best: &Individual, dims: GridDims) -> std::io::Result<()> {
        let rank = best.outcome.rank();
        if rank > self.best_rank || self.best_dims != Some(dims) {
            self.best_rank = rank;
            self.best_dims = Some(dims);
            write_json(
                &self.dir.join("best_genome.json"),
                &serde_json::json!({
                    "resolution": [dims.nx, dims.ny, dims.nz],
                    "genome": best.genome,
                    "outcome": best.outcome,
                }),
            )?;
        }
        Ok(())
    }

    pub fn finish(&mut self, summary: &RunSummary, scene: &Scene) -> std::io::Result<()> {
        let best = summary.best();
        write_json(
            &self.dir.join("best_genome.json"),
            &SavedIndividual {
                genome: &best.genome,
                outcome: &best.outcome,
            },
        )?;
        for (i, pop) in summary.populations.iter().enumerate() {
            let island_best = fittest(pop);
            write_json(
                &self.dir.join(format!("island-{i}-best.json")),
                &SavedIndividual {
                    genome: &island_best.genome,
                    outcome: &island_best.outcome,
                },
            )?;
        }
        let populations: Vec<Vec<SavedIndividual>> = summary
            .populations
            .iter()
            .map(|p| {
                p.iter()
                    .map(|i| SavedIndividual {
                        genome: &i.genome,
                        outcome: &i.outcome,
                    })
                    .collect()
            })
            .collect();
        write_json(&self.dir.join("population.json"), &populations)?;
        if let Some(front) = &summary.pareto {
            write_front(&self.dir.join("pareto.csv"), front)?;
            super::plots::write_front(&self.dir, &self.config.name, front)?;
        }

        let grid = scene.design(&best.genome, summary.dims);
        write_json(
            &self.dir.join("best_voxels.json"),
            &voxels_json(&grid, scene),
        )?;
        let mut exports = amorph::export::write_fabrication_files(
            &self.dir.join("exports"),
            &grid,
            scene,
            Some(&best.outcome),
        )?;
        exports.extend(amorph::export::write_smooth_surfaces(
            &self.dir.join("exports"),
            &best.genome,
            scene,
            summary.dims,
            SMOOTH_SAMPLES_AT_END,
        )?);
        let export = &self.config.export;
        // A run stopped by a signal is not finished (it resumes from its store), and the person
        // who stopped it is waiting: the end-of-run work that simulates or slices the best design
        // again (seconds for a beam's twice-finer check, minutes for a 20³ robot's walk) waits
        // for the run's real end.
        let finished = summary.stop != StopReason::Shutdown;
        if export.print && finished {
            // A stack too large for its pitch costs the slices, not the run's other results.
            match amorph::export::write_slice_stack(
                &self.dir.join("exports"),
                &best.genome,
                scene,
                summary.dims,
                export.pitch(),
            ) {
                // The report links the first slice and the manifest (the last file), not every
                // layer.
                Ok(files) => exports.extend(
                    files
                        .first()
                        .into_iter()
                        .chain(files.last().filter(|_| files.len() > 1))
                        .cloned(),
                ),
                Err(e) => tracing::warn!(error = %e, "the voxel-print slices were not written"),
            }
        }
        let finer = (export.finer_check && finished)
            .then(|| FinerCheck::run(scene, &best.genome, summary.dims, &best.outcome));
        let island_pictures = self.island_pictures(summary, scene)?;
        // The task's own pictures may simulate the best design once more (a robot's walk); a
        // failure there costs those pictures, not the run's other results.
        let artefacts = if finished {
            scene
                .write_artefacts(&self.dir, &best.genome, summary.dims, &best.outcome)
                .unwrap_or_else(|e| {
                    tracing::warn!(error = %e, "the task's pictures were not written");
                    Vec::new()
                })
        } else {
            Vec::new()
        };
        let name = &self.config.name;
        write_progress(&self.dir, name, summary, scene.figure_spec())?;
        let mut json = serde_json::json!({
            "name": name,
            "kind": scene.kind(),
            "stop": summary.stop,
            "epochs": summary.epochs,
            "evaluations": summary.evaluations,
            "unchanged_children": summary.unchanged_children,
            "wall_seconds": summary.wall_seconds,
            "resolution": summary.dims.to_string(),
            "best_fitness": best.outcome.fitness(),
        });
        if let (Some(json), Some(finer)) = (json.as_object_mut(), &finer) {
            json.insert("finer_check".into(), serde_json::json!(finer));
        }
        if let (Some(json), serde_json::Value::Object(task)) =
            (json.as_object_mut(), scene.summary(&best.outcome))
        {
            json.extend(task);
        }
        write_json(&self.dir.join("summary.json"), &json)?;
        std::fs::write(
            self.dir.join("summary.md"),
            summary_markdown(summary, name, scene),
        )?;
        let report = run_report(
            summary,
            &ReportInputs {
                dir: &self.dir,
                name,
                scene,
                exports: &exports,
                island_pictures: &island_pictures,
                artefacts: &artefacts,
                finer: finer.as_ref(),
                config_text: &self.config_text,
            },
        );
        std::fs::write(self.dir.join("report.md"), report.to_markdown())?;
        std::fs::write(self.dir.join("report.html"), report.to_html())
    }

    /// island-<i>-best.png: each island's best design at the final resolution.
    fn island_pictures(&self, summary: &RunSummary, scene: &Scene) -> std::io::Result<Vec<String>> {
        let mut names = Vec::new();
        for (i, pop) in summary.populations.iter().enumerate() {
            let best = fittest(pop);
            let grid = scene.design(&best.genome, summary.dims);
            let png = amorph::report::render_isometric(&grid, scene.palette(), 8.0)
                .to_png()
                .map_err(std::io::Error::other)?;
            let name = format!("island-{i}-best.png");
            std::fs::write(self.dir.join(&name), png)?;
            names.push(name);
        }
        Ok(names)
    }
}

/// A readable voxel file: for each Z layer (bottom up), one string per Y row with a character per
/// X cell: `.` empty, `0`–`9`/`a`–`f` the material index.
fn voxels_json(grid: &VoxelGrid, scene: &Scene) -> serde_json::Value {
    let d = grid.dims();
    let layers: Vec<Vec<String>> = (0..d.nz)
        .map(|z| {
            (0..d.ny)
                .map(|y| {
                    (0..d.nx)
                        .map(|x| match grid.get(x, y, z) {
                            None => '.',
                            Some(m) => char::from_digit(u32::from(m.0), 16).unwrap_or('?'),
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    let materials: Vec<&str> = scene.palette().0.iter().map(|m| m.name.as_str()).collect();
    serde_json::json!({ "dims": [d.nx, d.ny, d.nz], "materials": materials, "layers_z_up": layers })
}

fn write_json(path: &std::path::Path, value: &impl Serialize) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(std::io::Error::other)?;
    std::fs::write(path, text)
}

/// `pareto.csv`: a row per non-dominated design, ordered by the first objective (then by
/// evaluation), its evaluation id (`task_id` in the run store) and its objectives' values.
fn write_front(path: &std::path::Path, front: &Front) -> std::io::Result<()> {
    let mut out = BufWriter::new(File::create(path)?);
    let names: Vec<&str> = front.objectives.iter().map(|o| o.name).collect();
    writeln!(out, "task_id,{}", names.join(","))?;
    for (task, values) in front.along_first() {
        let values: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        writeln!(out, "{},{}", task.0, values.join(","))?;
    }
    out.flush()
}
