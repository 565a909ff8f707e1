//! `worker evaluate`: evaluates a saved genome in a scene at a resolution and prints the outcome.
//! `worker export`: writes a saved genome's fabrication files (STL, VXA, SVG layers).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(version, about = "Amorph worker: stateless evaluation of genomes")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Evaluates one genome (a genome JSON, or a results file such as best_genome.json) and prints
    /// its outcome as JSON.
    Evaluate {
        #[arg(long)]
        genome: PathBuf,
        /// A run config (its [scene] is used) or a bare scene TOML.
        #[arg(long)]
        scene: PathBuf,
        /// Resolution as NXxNYxNZ, e.g. 12x40x12 (a beam runs along y).
        #[arg(long)]
        resolution: String,
    },
    /// Writes the fabrication files of a genome (e.g. a run's best_genome.json) at a resolution:
    /// one STL per material (mm), design.vxa for VoxCAD/Voxelyze, one SVG per laser-cut layer.
    Export {
        #[arg(long)]
        genome: PathBuf,
        /// A run config (its [scene] is used) or a bare scene TOML.
        #[arg(long)]
        scene: PathBuf,
        /// Resolution as NXxNYxNZ, e.g. 12x40x12 (a beam runs along y).
        #[arg(long)]
        resolution: String,
        /// Folder to write into (created if missing).
        #[arg(long)]
        out: PathBuf,
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
        Command::Evaluate {
            genome,
            scene,
            resolution,
        } => {
            let genome = amorph_worker::read_genome(&genome)?;
            let scene = amorph_worker::read_scene(&scene)?;
            let dims = amorph_worker::parse_resolution(&resolution)?;
            let outcome = amorph_worker::evaluate(&genome, &scene, dims);
            println!(
                "{}",
                serde_json::to_string_pretty(&outcome).context("serialising the outcome")?
            );
        }
        Command::Export {
            genome,
            scene,
            resolution,
            out,
        } => {
            let genome = amorph_worker::read_genome(&genome)?;
            let scene = amorph_worker::read_scene(&scene)?;
            let dims = amorph_worker::parse_resolution(&resolution)?;
            genome
                .validate(scene.limits(), scene.palette().len())
                .context("the genome does not fit the scene")?;
            let grid = scene.design(&genome, dims);
            let files = amorph::export::write_fabrication_files(&out, &grid, &scene)
                .with_context(|| format!("writing into {}", out.display()))?;
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
