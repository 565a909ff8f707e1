//! The results folder of a run: written as the run goes, so a killed run keeps its history and its
//! best design so far.
//!
//! ```text
//! results/<name>/
//!   config.toml           the effective configuration (defaults filled in)
//!   history.csv           per epoch and island: evaluations, wall time, resolution, best and mean fitness
//!   best_genome.json      the best genome so far (updated whenever it improves)
//!   island-<i>-best.json  each island's best genome at the end
//!   population.json       every island's final population with outcomes
//!   best_voxels.json      the best design voxelized at the final resolution
//!   profile.csv           beam task: its top-surface profile against the target
//!   summary.json, summary.md   the final table
//!   exports/              fabrication files of the best design (STL, 3MF, VXA, SVG layers, PNG,
//!                         smooth STL of the genome's field)
//!   island-<i>-best.png   a render of each island's best design
//!   progress_evaluations.png, progress_wall_time.png, profile.png (beam)   plots
//!   animation.gif, trajectory.png, trajectory.csv   robot task: the best robot walking
//!   report.md, report.html     the run report: config, pictures, the paper-style table, links
//! ```

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use amorph::beam::BeamScene;
use amorph::export::{Block, Link, Picture, Report};
use amorph::genome::Genome;
use amorph::locomotion::LocomotionScene;
use amorph::outcome::Outcome;
use amorph::scene::Scene;
use amorph::voxel::{GridDims, VoxelGrid};
use serde::Serialize;

use crate::config::RunConfig;
use crate::run::{HistoryRow, RunSummary};
use crate::search::Individual;

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
        let text = toml::to_string_pretty(&config.raw).map_err(std::io::Error::other)?;
        std::fs::write(dir.join("config.toml"), &text)?;
        let mut history = BufWriter::new(File::create(dir.join("history.csv"))?);
        writeln!(
            history,
            "epoch,evaluations,wall_seconds,resolution,island,best_fitness,best_rms_percent,mean_fitness,replacements"
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
        writeln!(
            self.history,
            "{},{},{:.3},{},{},{},{},{},{}",
            row.epoch,
            row.evaluations,
            row.wall_seconds,
            row.resolution,
            row.island,
            opt(row.best_fitness),
            opt(row.best_rms_percent),
            opt(row.mean_fitness),
            row.replacements
        )?;
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
            let island_best = island_best(pop);
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

        let grid = scene.design(&best.genome, summary.dims);
        write_json(
            &self.dir.join("best_voxels.json"),
            &voxels_json(&grid, scene),
        )?;
        let mut exports =
            amorph::export::write_fabrication_files(&self.dir.join("exports"), &grid, scene)?;
        exports.extend(amorph::export::write_smooth_surfaces(
            &self.dir.join("exports"),
            &best.genome,
            scene,
            summary.dims,
            SMOOTH_SAMPLES_AT_END,
        )?);
        let island_pictures = self.island_pictures(summary, scene)?;
        if let (Scene::Locomotion(robot), Some(_)) = (scene, best.outcome.locomotion_metrics()) {
            // One more simulation of the best robot, recorded densely; a failure here costs the
            // pictures, not the run's other results.
            if let Err(e) = amorph::export::write_locomotion_pictures(
                &self.dir,
                &best.genome,
                robot,
                summary.dims,
            ) {
                tracing::warn!(error = %e, "robot animation and trajectory not written");
            }
        }
        self.plots(summary, best)?;
        let common = serde_json::json!({
            "name": self.config.raw.name,
            "stop": summary.stop,
            "epochs": summary.epochs,
            "evaluations": summary.evaluations,
            "wall_seconds": summary.wall_seconds,
            "resolution": summary.dims.to_string(),
            "best_fitness": best.outcome.fitness(),
        });
        let (task, md) = match scene {
            Scene::Beam(beam) => self.beam_summary(beam, best, summary)?,
            Scene::Locomotion(_) => locomotion_summary(&self.config.raw.name, best, summary),
        };
        let mut json = common;
        if let (Some(json), Some(task)) = (json.as_object_mut(), task.as_object()) {
            json.extend(task.clone());
        }
        write_json(&self.dir.join("summary.json"), &json)?;
        std::fs::write(self.dir.join("summary.md"), md)?;
        let report = self.report(summary, scene, &exports, &island_pictures);
        std::fs::write(self.dir.join("report.md"), report.to_markdown())?;
        std::fs::write(self.dir.join("report.html"), report.to_html())
    }

    /// island-<i>-best.png: each island's best design at the final resolution.
    fn island_pictures(&self, summary: &RunSummary, scene: &Scene) -> std::io::Result<Vec<String>> {
        let mut names = Vec::new();
        for (i, pop) in summary.populations.iter().enumerate() {
            let best = island_best(pop);
            let grid = scene.design(&best.genome, summary.dims);
            let png = amorph::export::render_isometric(&grid, scene.palette(), 8.0)
                .to_png()
                .map_err(std::io::Error::other)?;
            let name = format!("island-{i}-best.png");
            std::fs::write(self.dir.join(&name), png)?;
            names.push(name);
        }
        Ok(names)
    }

    /// The run report: what ran, the paper-style table, the pictures, links to every file and
    /// the configuration. Only files that exist are linked, so every link resolves.
    fn report(
        &self,
        summary: &RunSummary,
        scene: &Scene,
        exports: &[PathBuf],
        island_pictures: &[String],
    ) -> Report {
        let best = summary.best();
        let exists = |name: &str| self.dir.join(name).is_file();
        let picture = |path: &str, caption: &str| Picture {
            path: path.into(),
            caption: caption.into(),
        };
        let mut report = Report::new(format!("Amorph run {}", self.config.raw.name));
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
        match scene {
            Scene::Beam(beam) => {
                report.push(Block::Heading(
                    "Shape-matching error (paper Table III)".into(),
                ));
                report.push(beam_table(beam, best, summary));
            }
            Scene::Locomotion(robot) => {
                report.push(Block::Heading("Locomotion speed (paper Table IV)".into()));
                report.push(locomotion_table(robot, best, summary));
            }
        }

        report.push(Block::Heading("Best design".into()));
        let mut pictures = vec![picture("exports/design.png", "best design, isometric view")];
        for (file, caption) in [
            ("profile.png", "deflected top surface against the target"),
            ("animation.gif", "the best robot walking (10x slow motion)"),
            (
                "trajectory.png",
                "centre of mass: x against time, and the path seen from above",
            ),
        ] {
            if exists(file) {
                pictures.push(picture(file, caption));
            }
        }
        report.push(Block::Pictures(pictures));
        report.push(Block::Heading("Best design of each island".into()));
        report.push(Block::Pictures(
            island_pictures
                .iter()
                .enumerate()
                .map(|(i, p)| picture(p, &format!("island {i}")))
                .collect(),
        ));
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
            exports
                .iter()
                .map(|p| {
                    let path = format!("exports/{}", p.display());
                    Link {
                        label: export_label(p),
                        path,
                    }
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
            "profile.csv",
            "trajectory.csv",
            "summary.json",
            "summary.md",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
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
            text: self.config_text.clone(),
        });
        report
    }

    /// progress.png (the best of each island against evaluations and against wall time) and, for
    /// a beam, profile.png (the deflected top surface against its target).
    fn plots(&self, summary: &RunSummary, best: &Individual) -> std::io::Result<()> {
        use amorph::export::{PlotSpec, Series, line_plot};
        let beam = best.outcome.beam_metrics().is_some();
        let islands = summary.populations.len();
        let palette = [
            [31, 119, 180],
            [214, 39, 40],
            [44, 160, 44],
            [148, 103, 189],
            [255, 127, 14],
            [23, 190, 207],
        ];
        let figure = |x_of: &dyn Fn(&crate::run::HistoryRow) -> f64, x_label: &str| {
            let series: Vec<Series> = (0..islands)
                .map(|i| Series {
                    label: format!("island {i}"),
                    colour: palette[i % palette.len()],
                    markers: false,
                    points: summary
                        .history
                        .iter()
                        .filter(|r| r.island as usize == i)
                        .filter_map(|r| {
                            let y = if beam {
                                r.best_rms_percent?
                            } else {
                                1e3 * r.best_fitness?
                            };
                            Some([x_of(r), y])
                        })
                        .collect(),
                })
                .collect();
            let spec = PlotSpec {
                title: format!("{}: best design per island", self.config.raw.name),
                x_label: x_label.into(),
                y_label: if beam {
                    "RMS ERROR (% OF TIP DEFLECTION)".into()
                } else {
                    "DISPLACEMENT (MM)".into()
                },
                log_x: false,
                log_y: beam,
            };
            line_plot(&spec, &series)
                .to_png()
                .map_err(std::io::Error::other)
        };
        std::fs::write(
            self.dir.join("progress_evaluations.png"),
            figure(&|r| r.evaluations as f64, "EVALUATIONS")?,
        )?;
        std::fs::write(
            self.dir.join("progress_wall_time.png"),
            figure(&|r| r.wall_seconds, "WALL TIME (S)")?,
        )?;
        if let Some(m) = best.outcome.beam_metrics() {
            let pick = |k: usize| m.profile.iter().map(|p| [p[0], p[k]]).collect();
            let series = [
                Series {
                    label: "TARGET".into(),
                    colour: [120, 120, 120],
                    markers: false,
                    points: pick(2),
                },
                Series {
                    label: "SIMULATED".into(),
                    colour: [214, 39, 40],
                    markers: true,
                    points: pick(1),
                },
            ];
            let spec = PlotSpec {
                title: format!("TOP SURFACE, RMS {:.3} %", m.rms_percent),
                x_label: "POSITION ALONG THE BEAM (CLAMP 0, TIP 1)".into(),
                y_label: "DEFLECTION / TIP DEFLECTION".into(),
                log_x: false,
                log_y: false,
            };
            let png = line_plot(&spec, &series)
                .to_png()
                .map_err(std::io::Error::other)?;
            std::fs::write(self.dir.join("profile.png"), png)?;
        }
        Ok(())
    }

    /// The beam's profile.csv, and its summary fields and Table-III-style line.
    fn beam_summary(
        &self,
        beam: &BeamScene,
        best: &Individual,
        summary: &RunSummary,
    ) -> std::io::Result<(serde_json::Value, String)> {
        let metrics = best.outcome.beam_metrics();
        if let Some(m) = metrics {
            let mut csv = String::from("t,simulated,target\n");
            for [t, w, f] in &m.profile {
                csv.push_str(&format!("{t},{w},{f}\n"));
            }
            std::fs::write(self.dir.join("profile.csv"), csv)?;
        }
        let rms = metrics.map(|m| m.rms_percent);
        let paper = beam.target.paper_rms_percent();
        let json = serde_json::json!({
            "target": beam.target.name(),
            "best_rms_percent": rms,
            "paper_rms_percent": paper,
            "voxels": metrics.map(|m| m.voxels),
            "material_counts": metrics.map(|m| m.material_counts.clone()),
        });
        let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3} %"));
        let md = format!(
            "# Run `{}`\n\n| target | best RMS error | paper (simulated) | evaluations | wall time | resolution | stop |\n|---|---|---|---|---|---|---|\n| {} | {} | {} | {} | {:.1} s | {} | {:?} |\n",
            self.config.raw.name,
            beam.target.name(),
            fmt(rms),
            fmt(paper),
            summary.evaluations,
            summary.wall_seconds,
            summary.dims,
            summary.stop,
        );
        Ok((json, md))
    }
}

/// The robot's summary fields and Table-IV-style line (the paper's robot: 3.38 % body length per
/// cycle).
fn locomotion_summary(
    name: &str,
    best: &Individual,
    summary: &RunSummary,
) -> (serde_json::Value, String) {
    let m = best.outcome.locomotion_metrics();
    let json = serde_json::json!({
        "task": "locomotion",
        "displacement_m": m.map(|m| m.displacement),
        "gait_displacement_m": m.map(|m| m.gait_displacement),
        "speed_percent_body_length_per_cycle": m.map(|m| m.speed_percent_per_cycle),
        "paper_speed_percent_body_length_per_cycle": 3.38,
        "body_length_m": m.map(|m| m.body_length),
        "voxels": m.map(|m| m.voxels),
        "material_counts": m.map(|m| m.material_counts.clone()),
        "centre_of_mass_trace": m.map(|m| m.centre_of_mass_trace.clone()),
    });
    let fmt = |v: Option<f64>, unit: &str| v.map_or("-".to_string(), |v| format!("{v:.3}{unit}"));
    let md = format!(
        "# Run `{name}`\n\n| task | gait travel (fitness) | total travel | speed (body lengths/cycle) | paper | voxels | evaluations | wall time | resolution | stop |\n|---|---|---|---|---|---|---|---|---|---|\n| locomotion | {} | {} | {} | 3.38 % | {} | {} | {:.1} s | {} | {:?} |\n",
        fmt(m.map(|m| 1e3 * m.gait_displacement), " mm"),
        fmt(m.map(|m| 1e3 * m.displacement), " mm"),
        fmt(m.map(|m| m.speed_percent_per_cycle), " %"),
        m.map_or("-".to_string(), |m| m.voxels.to_string()),
        summary.evaluations,
        summary.wall_seconds,
        summary.dims,
        summary.stop,
    );
    (json, md)
}

/// The fittest individual of one island's population (the lowest slot on a tie).
fn island_best(pop: &[Individual]) -> &Individual {
    pop.iter().fold(&pop[0], |b, ind| {
        if ind.outcome.is_fitter_than(&b.outcome) {
            ind
        } else {
            b
        }
    })
}

/// Table III's columns for this run's best beam, with the paper's simulated error beside it.
fn beam_table(beam: &BeamScene, best: &Individual, summary: &RunSummary) -> Block {
    let percent = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3} %"));
    Block::Table {
        header: [
            "target",
            "RMS error (% of tip deflection)",
            "paper, simulated",
            "evaluations",
            "resolution",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![vec![
            beam.target.name().to_string(),
            percent(best.outcome.beam_metrics().map(|m| m.rms_percent)),
            percent(beam.target.paper_rms_percent()),
            summary.evaluations.to_string(),
            summary.dims.to_string(),
        ]],
    }
}

/// Table IV's quantities for this run's best robot beside the paper's simulated robot (18 mm,
/// 1.675 g, printed as 1.675×10⁻³ (kg), 0.07 s period, 3.38 % of body length per cycle).
fn locomotion_table(robot: &LocomotionScene, best: &Individual, summary: &RunSummary) -> Block {
    let m = best.outcome.locomotion_metrics();
    let dims = summary.dims;
    let s = robot.dynamics_at(dims).voxel_size;
    let mass_mg = m.map(|m| {
        let kg: f64 = m
            .material_counts
            .iter()
            .zip(&robot.palette.0)
            .map(|(&n, material)| n as f64 * material.density * s.powi(3))
            .sum();
        1e6 * kg
    });
    let period = robot.dynamics.actuation.as_ref().map(|a| a.period);
    let num = |v: Option<f64>, digits: usize, unit: &str| {
        v.map_or("-".to_string(), |v| format!("{v:.digits$}{unit}"))
    };
    let row =
        |name: &str, ours: String, paper: &str| vec![name.to_string(), ours, paper.to_string()];
    Block::Table {
        header: ["", "this run (simulated)", "paper (simulated)"]
            .map(String::from)
            .to_vec(),
        rows: vec![
            row(
                "body length",
                num(m.map(|m| 1e3 * m.body_length), 2, " mm"),
                "18 mm",
            ),
            row(
                "voxels",
                m.map_or("-".into(), |m| format!("{} at {dims}", m.voxels)),
                "20x20x20 workspace",
            ),
            row(
                "mass",
                num(mass_mg, 3, " mg"),
                "1,675 mg (Table IV: 1.675×10⁻³, read as kg)",
            ),
            row("actuation period", num(period, 3, " s"), "0.07 s"),
            row(
                "actuation cycles",
                robot.dynamics.actuation_cycles.to_string(),
                "-",
            ),
            row(
                "gait travel (fitness: median cycle × cycles)",
                num(m.map(|m| 1e3 * m.gait_displacement), 3, " mm"),
                "-",
            ),
            row(
                "total travel of the centre of mass",
                num(m.map(|m| 1e3 * m.displacement), 3, " mm"),
                "-",
            ),
            row(
                "speed (% body length per cycle)",
                num(m.map(|m| m.speed_percent_per_cycle), 3, " %"),
                "3.38 %",
            ),
        ],
    }
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
fn export_label(path: &std::path::Path) -> String {
    let name = path.display().to_string();
    let what = match path.extension().and_then(|e| e.to_str()) {
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
