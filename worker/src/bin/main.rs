//! `worker evaluate`: evaluates a saved genome in a scene at a resolution and prints the outcome.
//! `worker export`: writes a saved genome's fabrication files (STL, VXA, SVG layers) and, for a
//! robot, its animation and trajectory.

use std::path::PathBuf;

use amorph::genome::Genome;
use amorph::scene::Scene;
use amorph::voxel::GridDims;
use anyhow::Context;
use clap::{Args, Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(version, about = "Amorph worker: stateless evaluation of genomes")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// A saved genome in a scene at a resolution: what both commands start from.
#[derive(Debug, Args)]
struct Design {
    /// A genome JSON, or a results file holding one such as best_genome.json.
    #[arg(long)]
    genome: PathBuf,
    /// A run config (its [scene] is used) or a bare scene TOML.
    #[arg(long)]
    scene: PathBuf,
    /// Resolution as NXxNYxNZ, e.g. 12x40x12 (a beam runs along y).
    #[arg(long)]
    resolution: String,
}

impl Design {
    fn load(&self) -> anyhow::Result<(Genome, Scene, GridDims)> {
        Ok((
            amorph_worker::read_genome(&self.genome)?,
            amorph_worker::read_scene(&self.scene)?,
            amorph_worker::parse_resolution(&self.resolution)?,
        ))
    }
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Evaluates one genome and prints its outcome as JSON.
    Evaluate {
        #[command(flatten)]
        design: Design,
    },
    /// Writes the fabrication files of a genome at a resolution: one STL per material (mm),
    /// design.3mf, design.vxa for VoxCAD/Voxelyze, design.png and one SVG per laser-cut layer;
    /// for a robot also animation.gif and trajectory.png/.csv (it is simulated once more).
    Export {
        #[command(flatten)]
        design: Design,
        /// Folder to write into (created if missing).
        #[arg(long)]
        out: PathBuf,
        /// Also write material-<i>-<name>-smooth.stl: each material's region of the genome's
        /// continuous field, meshed with about N samples along the longest side (rounded to a
        /// whole number per voxel).
        #[arg(long, value_name = "N")]
        smooth: Option<usize>,
    },
}

fn main() -> std::process::ExitCode {
    match try_main(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn try_main(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Evaluate { design } => {
            let (genome, scene, dims) = design.load()?;
            let outcome = amorph_worker::evaluate(&genome, &scene, dims);
            println!(
                "{}",
                serde_json::to_string_pretty(&outcome).context("serialising the outcome")?
            );
        }
        Command::Export {
            design,
            out,
            smooth,
        } => {
            let (genome, scene, dims) = design.load()?;
            genome
                .validate(scene.limits(), scene.palette().len())
                .context("the genome does not fit the scene")?;
            let grid = scene.design(&genome, dims);
            let mut files = amorph::export::write_fabrication_files(&out, &grid, &scene)
                .with_context(|| format!("writing into {}", out.display()))?;
            if let Some(samples) = smooth {
                files.extend(
                    amorph::export::write_smooth_surfaces(&out, &genome, &scene, dims, samples)
                        .with_context(|| {
                            format!("writing smooth surfaces into {}", out.display())
                        })?,
                );
            }
            if let Scene::Locomotion(robot) = &scene {
                files.extend(
                    amorph::export::write_locomotion_pictures(&out, &genome, robot, dims)
                        .with_context(|| format!("animating the robot into {}", out.display()))?,
                );
            }
            println!(
                "{} voxels; wrote {} files into {}",
                grid.filled_count(),
                files.len(),
                out.display()
            );
        }
    }
    Ok(())
}
