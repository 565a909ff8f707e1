//! `worker --connect URL`: a stateless cluster worker that pulls tasks from a coordinator.
//! `worker evaluate`: evaluates a saved genome in a scene at a resolution and prints the outcome.
//! `worker export`: writes a saved genome's fabrication files (STL, VXA, SVG layers) and, for a
//! robot, its animation and trajectory.

use std::path::PathBuf;

use amorph::dynamics::EvaluationThreads;
use amorph::export::PrintPitch;
use amorph::genome::Genome;
use amorph::task::Scene;
use amorph::voxel::GridDims;
use amorph_worker::export::{ExportOptions, export_design};
use amorph_worker::{WorkerOptions, run_worker};
use anyhow::Context;
use clap::{Args, Parser, Subcommand};
use tracing_subscriber::EnvFilter;

#[derive(Debug, Parser)]
#[command(
    version,
    about = "Amorph worker: stateless evaluation of genomes",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(flatten)]
    connect: Connect,
    #[command(subcommand)]
    command: Option<Command>,
}

/// Serving a coordinator: `worker --connect http://host:50051`.
#[derive(Debug, Args)]
struct Connect {
    /// The coordinator's URL: http://HOST:PORT, or https://HOST:PORT when it serves TLS.
    #[arg(long)]
    connect: Option<String>,
    /// Evaluations at once (default: one per core, divided by --threads-per-evaluation).
    #[arg(long)]
    threads: Option<usize>,
    /// Threads that share each evaluation (default 1). The outcome is the same bits for any
    /// count; more pays when evaluations are fewer than cores (large robots, small batches).
    #[arg(long, default_value_t = 1)]
    threads_per_evaluation: usize,
    /// Shared secret the coordinator requires, or this worker's own credential.
    #[arg(long, env = "AMORPH_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// File holding the token (a credential from `coordinator credentials add NAME`, or the
    /// shared secret); surrounding whitespace is ignored. Takes precedence over --token and
    /// AMORPH_TOKEN.
    #[arg(long, env = "AMORPH_TOKEN_FILE")]
    token_file: Option<PathBuf>,
    /// Name shown in the coordinator's logs and run store (default: host:pid).
    #[arg(long)]
    name: Option<String>,
    /// PEM certificate of the authority that signed the coordinator's TLS certificate.
    #[arg(long)]
    ca: Option<PathBuf>,
    /// Name to check the coordinator's certificate against, if not the URL's host.
    #[arg(long)]
    tls_domain: Option<String>,
    /// Keep waiting for the next run when one finishes, instead of exiting.
    #[arg(long)]
    stay: bool,
    /// Give up after this many seconds without reaching the coordinator (default: never).
    #[arg(long)]
    give_up_after: Option<f64>,
    /// On SIGTERM, seconds to let running evaluations finish before handing them back.
    #[arg(long, default_value_t = 30.0)]
    grace_seconds: f64,
    /// Memory all evaluations at once may use, e.g. 8G or 512M (default: half the machine's).
    /// A task whose estimated need exceeds this divided by the threads is refused, not started.
    #[arg(long)]
    max_memory: Option<String>,
    /// Log level when RUST_LOG is not set.
    #[arg(long, default_value = "warn")]
    log: String,
}

/// A saved genome in a scene at a resolution: what both commands start from.
#[derive(Debug, Args)]
struct Design {
    /// A genome JSON, or a results file holding one such as best_genome.json.
    #[arg(long, required_unless_present = "run", conflicts_with = "run")]
    genome: Option<PathBuf>,
    /// A run config (its [scene] is used) or a bare scene TOML.
    #[arg(long, required_unless_present = "run", conflicts_with = "run")]
    scene: Option<PathBuf>,
    /// Resolution as NXxNYxNZ, e.g. 12x40x12 (a beam runs along y); with --run, the design's own
    /// evaluation's unless given.
    #[arg(long, required_unless_present = "run")]
    resolution: Option<String>,
    /// A run folder (results/<name>): the design is its evaluation --design, its scene the run's.
    #[arg(long, requires = "design_id")]
    run: Option<PathBuf>,
    /// The evaluation's id in the run (task_id, as pareto.csv and run.sqlite give it).
    #[arg(long = "design", id = "design_id", requires = "run")]
    design_id: Option<u64>,
    /// Threads that share the simulation (default 1); the outcome is the same bits for any count.
    #[arg(long, default_value_t = 1)]
    threads: usize,
}

impl Design {
    /// The pool of `--threads` threads an evaluation shares (the calling thread alone for 1).
    fn threads(&self) -> anyhow::Result<EvaluationThreads> {
        let threads = thread_count("--threads", self.threads)?;
        EvaluationThreads::new(threads, |j| format!("evaluate-{j}"))
            .with_context(|| format!("starting {threads} threads"))
    }

    fn load(&self) -> anyhow::Result<(Genome, Scene, GridDims)> {
        let resolution = (self.resolution.as_deref()).map(amorph_worker::parse_resolution);
        if let (Some(run), Some(id)) = (&self.run, self.design_id) {
            let (genome, scene, stored) = amorph_worker::read_run_design(run, id)?;
            return Ok((genome, scene, resolution.transpose()?.unwrap_or(stored)));
        }
        let given = "clap requires --genome, --scene and --resolution without --run";
        Ok((
            amorph_worker::read_genome(self.genome.as_ref().expect(given))?,
            amorph_worker::read_scene(self.scene.as_ref().expect(given))?,
            resolution.expect(given)?,
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
    /// for a robot also voxcraft/base.vxa and voxcraft/design.vxd for voxcraft-sim, animation.gif
    /// and trajectory.png/.csv (it is simulated once more).
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
        /// Also write slices/: a voxel-print slice stack (one PNG per printed layer, sampled from
        /// the genome's continuous field) and its manifest.
        #[arg(long)]
        print: bool,
        /// The printer's dots per inch along x and y, for --print.
        #[arg(long, value_name = "X,Y", value_delimiter = ',', num_args = 2, default_values_t = [600.0, 300.0])]
        print_dpi: Vec<f64>,
        /// The printer's layer thickness in millimetres, for --print.
        #[arg(long, value_name = "MM", default_value_t = 0.027)]
        print_layer_mm: f64,
    },
}

fn main() -> std::process::ExitCode {
    amorph::heap::keep_freed_memory();
    match try_main(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn try_main(cli: Cli) -> anyhow::Result<()> {
    let Some(command) = cli.command else {
        return serve(cli.connect);
    };
    match command {
        Command::Evaluate { design } => {
            let (genome, scene, dims) = design.load()?;
            amorph::task::memory::check(&scene, dims, amorph::task::memory::default_budget())?;
            let outcome = design.threads()?.run(|| scene.evaluate(&genome, dims));
            print(&serde_json::to_string_pretty(&outcome).context("serialising the outcome")?)?;
        }
        Command::Export {
            design,
            out,
            smooth,
            print: slices,
            print_dpi,
            print_layer_mm,
        } => {
            let (genome, scene, dims) = design.load()?;
            let options = ExportOptions {
                smooth,
                print: slices.then(|| PrintPitch {
                    dpi_x: print_dpi[0],
                    dpi_y: print_dpi[1],
                    layer_mm: print_layer_mm,
                }),
            };
            // The task's own pictures (a beam's profile, a robot's walk) and a robot's VXA (its
            // measured settle) need its evaluation.
            let threads = design.threads()?;
            let exported = export_design(&genome, &scene, dims, &out, options, || {
                threads.run(|| scene.evaluate(&genome, dims))
            })?;
            print(&format!(
                "{} voxels, {}; wrote {} files into {}",
                exported.voxels,
                scene
                    .headline(&exported.outcome)
                    .unwrap_or_else(|| format!("{:?}", exported.outcome)),
                exported.files.len(),
                out.display()
            ))?;
        }
    }
    Ok(())
}

/// Writes a line to stdout. A closed pipe (`worker evaluate | head`) ends the output quietly
/// instead of panicking as `println!` does.
fn print(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    match writeln!(std::io::stdout().lock(), "{text}") {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e).context("writing to stdout"),
        _ => Ok(()),
    }
}

/// `n` for a thread-count flag, or one line naming the flag and its bounds.
fn thread_count(flag: &str, n: usize) -> anyhow::Result<usize> {
    let max = amorph_worker::client::MAX_THREADS;
    anyhow::ensure!(
        (1..=max).contains(&n),
        "{flag} {n} must be between 1 and {max}"
    );
    Ok(n)
}

fn serve(c: Connect) -> anyhow::Result<()> {
    let Some(url) = c.connect else {
        anyhow::bail!("give --connect URL to serve a coordinator, or a command (see --help)");
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(&c.log)),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let per_evaluation = thread_count("--threads-per-evaluation", c.threads_per_evaluation)?;
    let threads = thread_count(
        "--threads",
        c.threads.unwrap_or_else(|| {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            (cores / per_evaluation).max(1)
        }),
    )?;
    let seconds = |name: &str, s: f64| {
        anyhow::ensure!(
            s.is_finite() && s >= 0.0,
            "{name} must be a non-negative number of seconds"
        );
        Ok(std::time::Duration::from_secs_f64(s))
    };
    let mut opts = WorkerOptions::new(url, threads);
    opts.threads_per_evaluation = per_evaluation;
    if let Some(name) = c.name {
        opts.name = name;
    }
    opts.token = match &c.token_file {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| anyhow::anyhow!("--token-file {}: {e}", path.display()))?;
            let token = text.trim();
            anyhow::ensure!(
                !token.is_empty(),
                "--token-file {} is empty",
                path.display()
            );
            Some(token.to_owned())
        }
        None => c.token.filter(|t| !t.is_empty()),
    };
    opts.ca_cert = c.ca;
    opts.tls_domain = c.tls_domain;
    opts.exit_when_finished = !c.stay;
    opts.give_up_after = c
        .give_up_after
        .map(|s| seconds("--give-up-after", s))
        .transpose()?;
    opts.grace = seconds("--grace-seconds", c.grace_seconds)?;
    opts.max_memory = c
        .max_memory
        .as_deref()
        .map(amorph::task::memory::parse_size)
        .transpose()
        .map_err(|e| anyhow::anyhow!("--max-memory {e}"))?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let summary = runtime.block_on(async move {
        let (stop, stop_rx) = tokio::sync::watch::channel(false);
        tokio::spawn(async move {
            amorph_proto::signal::termination().await;
            eprintln!(
                "worker: stopping (finishing running evaluations, then handing back the rest)"
            );
            let _ = stop.send(true);
        });
        run_worker(opts, stop_rx).await
    })?;
    eprintln!(
        "worker: evaluated {}, reported {} ({} duplicates), handed back {}, sessions {}",
        summary.evaluated, summary.reported, summary.duplicates, summary.released, summary.sessions
    );
    Ok(())
}
