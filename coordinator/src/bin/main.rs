//! `coordinator --config run.toml`: runs an evolutionary design job.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use amorph_coordinator::progress::Progress;
use amorph_coordinator::{LocalEvaluator, RunConfig, run};
use anyhow::Context;
use clap::Parser;
use tracing_subscriber::EnvFilter;

/// Evolves freeform multi-material designs (Hiller & Lipson 2012) and writes the results folder.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Cli {
    /// The run configuration (TOML); see configs/ for examples.
    #[arg(long)]
    config: PathBuf,
    /// Local evaluation threads, overriding `evaluation.threads` (0 = one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Log level when RUST_LOG is not set (error, warn, info, debug, trace).
    #[arg(long, default_value = "warn")]
    log: String,
}

fn main() -> std::process::ExitCode {
    // One line per error, causes joined with ': ', so a bad config reads as a single message.
    match try_main(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn try_main(cli: Cli) -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(&cli.log)),
        )
        .with_writer(std::io::stderr)
        .init();
    let mut config = RunConfig::load(&cli.config)?;
    if let Some(threads) = cli.threads {
        config.raw.evaluation.threads = threads;
    }
    let mut evaluator = LocalEvaluator::new(
        Arc::new(config.raw.scene.clone()),
        config.raw.evaluation.threads,
    );
    let progress = Progress::stderr(config.raw.budget.evaluations);
    let shutdown = AtomicBool::new(false);
    let summary = run(&config, &mut evaluator, &shutdown, &progress)
        .with_context(|| format!("run '{}' failed", config.raw.name))?;
    let best = summary.best();
    let headline = best.outcome.headline().unwrap_or_else(|| "-".into());
    println!(
        "{}: best {headline} at {} after {} evaluations in {:.1} s ({:?}); results in {}",
        config.raw.name,
        summary.dims,
        summary.evaluations,
        summary.wall_seconds,
        summary.stop,
        config.run_dir().display()
    );
    Ok(())
}
