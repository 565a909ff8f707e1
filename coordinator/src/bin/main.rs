//! `coordinator --config run.toml`: runs an evolutionary design job on a cluster of workers (by
//! default, workers inside this process; `worker --connect URL` processes may join at any time).
//! Without `--config` it runs the quickstart compiled into it.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use amorph_coordinator::RunConfig;
use amorph_coordinator::config::Override;
use amorph_coordinator::job::{JobOptions, StoreMode, run_job};
use amorph_coordinator::progress::Progress;
use amorph_coordinator::store::RunStore;
use anyhow::Context;
use clap::Parser;
use tracing_subscriber::EnvFilter;

/// Evolves freeform multi-material designs (Hiller & Lipson 2012) and writes the results folder.
#[derive(Debug, Parser)]
#[command(version, about, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// The run configuration (TOML); see configs/ for examples. Without it: the quickstart
    /// (configs/quickstart.toml, compiled in).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Overrides one config key, e.g. `--set scene.target=polynomial4` (a dotted key path and a
    /// TOML value; repeatable, applied in order, recorded in the run's config.toml).
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_override, conflicts_with = "health_check")]
    overrides: Vec<Override>,
    /// Continue the run in <results_dir>/<name>/run.sqlite (after a crash or Ctrl-C). The result is
    /// bit-identical to a run that was never interrupted.
    #[arg(long, conflicts_with_all = ["fresh", "resume_if_present"])]
    resume: bool,
    /// Resume if the run store exists, else start the run: for containers that may be restarted.
    #[arg(long, conflicts_with = "fresh")]
    resume_if_present: bool,
    /// Only ask the coordinator at this URL whether it is serving (gRPC health), exit 0 if so: the
    /// container health check, which has no shell or curl to use.
    #[arg(long, value_name = "URL", conflicts_with = "config")]
    health_check: Option<String>,
    /// Delete an existing run store of this config and start over.
    #[arg(long)]
    fresh: bool,
    /// Address to serve workers on, overriding `cluster.listen` (e.g. 0.0.0.0:50051).
    #[arg(long)]
    listen: Option<String>,
    /// Workers inside this process, overriding `cluster.local_workers` (0: external workers only).
    #[arg(long)]
    local_workers: Option<usize>,
    /// Serve the live dashboard on this address while the run goes (e.g. 127.0.0.1:8080),
    /// overriding `dashboard.listen`; open it in a browser (docs/how-to/dashboard.md).
    #[arg(long, value_name = "ADDR")]
    dashboard: Option<String>,
    /// Only read and check the config (with its `--set`s and preset), print the effective
    /// config.toml the run would record, and exit: nothing runs, nothing is written.
    #[arg(long, conflicts_with = "health_check")]
    check: bool,
    /// Log level when RUST_LOG is not set (error, warn, info, debug, trace).
    #[arg(long, default_value = "warn")]
    log: String,
}

#[derive(Debug, clap::Subcommand)]
enum Command {
    /// Per-worker credentials: each is a principal of its own, so workers under different
    /// credentials check each other's outcomes (docs/how-to/cluster.md).
    #[command(subcommand)]
    Credentials(CredentialsCommand),
    /// Serves the dashboard of a run from its store (results/<run>/run.sqlite), finished or still
    /// being written by another process, until Ctrl-C.
    Dashboard {
        /// The run's store.
        store: PathBuf,
        /// Address to serve the page on (port 0 picks a free one).
        #[arg(long, default_value = "127.0.0.1:8080")]
        listen: String,
        /// File holding the token a browser must present when listening beyond loopback
        /// (AMORPH_TOKEN, if set, takes precedence).
        #[arg(long)]
        token_file: Option<PathBuf>,
    },
}

#[derive(Debug, clap::Subcommand)]
enum CredentialsCommand {
    /// Issues a credential: appends its digest to FILE and writes its token, readable by you
    /// alone, to --token-out (default NAME.token beside FILE). Give that file to one worker:
    /// `worker --connect URL --token-file NAME.token`.
    Add {
        name: String,
        /// The credentials file (`cluster.credentials_file`); made if missing.
        #[arg(long, default_value = "credentials")]
        file: PathBuf,
        #[arg(long)]
        token_out: Option<PathBuf>,
    },
    /// Withdraws a credential (a running coordinator keeps it until restarted).
    Remove {
        name: String,
        #[arg(long, default_value = "credentials")]
        file: PathBuf,
    },
    /// Lists the credentials' names.
    List {
        #[arg(long, default_value = "credentials")]
        file: PathBuf,
    },
}

fn credentials(command: CredentialsCommand) -> anyhow::Result<()> {
    use amorph_coordinator::cluster::credentials::{Credentials, default_token_path};
    match command {
        CredentialsCommand::Add {
            name,
            file,
            token_out,
        } => {
            let out = token_out.unwrap_or_else(|| default_token_path(&file, &name));
            Credentials::add(&file, &name, &out)?;
            println!(
                "credential {name} added to {}; its token is in {} (give it to that worker alone)",
                file.display(),
                out.display()
            );
        }
        CredentialsCommand::Remove { name, file } => {
            Credentials::remove(&file, &name)?;
            println!("credential {name} removed from {}", file.display());
        }
        CredentialsCommand::List { file } => {
            for name in Credentials::load(&file)?.names() {
                println!("{name}");
            }
        }
    }
    Ok(())
}

fn parse_override(text: &str) -> Result<Override, String> {
    text.parse()
}

fn main() -> std::process::ExitCode {
    amorph::heap::keep_freed_memory();
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
    if let Some(url) = &cli.health_check {
        return health_check(url);
    }
    tracing_subscriber::fmt()
        .with_env_filter(
            EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(&cli.log)),
        )
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    match cli.command {
        Some(Command::Credentials(command)) => return credentials(command),
        Some(Command::Dashboard {
            store,
            listen,
            token_file,
        }) => return dashboard(&store, &listen, token_file.as_deref()),
        None => {}
    }
    let config = match &cli.config {
        Some(path) => RunConfig::load_with(path, &cli.overrides)?,
        None => RunConfig::quickstart(&cli.overrides)?,
    };
    if cli.check {
        print!("{}", toml::to_string_pretty(&config.to_raw())?);
        return Ok(());
    }
    let shutdown = Arc::new(AtomicBool::new(false));
    stop_on_signal(shutdown.clone());
    let (tx, rx) = std::sync::mpsc::channel();
    let (dashboard_tx, dashboard_rx) = std::sync::mpsc::channel();
    let options = JobOptions {
        store: if cli.resume || (cli.resume_if_present && RunStore::path_for(&config).exists()) {
            StoreMode::Resume
        } else if cli.fresh {
            StoreMode::Fresh
        } else {
            StoreMode::New
        },
        listen: cli.listen,
        local_workers: cli.local_workers,
        token: None,
        progress: Progress::stderr(config.budget.evaluations),
        shutdown: shutdown.clone(),
        on_listening: Some(tx),
        dashboard: cli.dashboard,
        on_dashboard: Some(dashboard_tx),
    };
    // Say where workers can connect, as soon as the server listens, and where the dashboard is.
    std::thread::spawn(move || {
        if let Ok(addr) = rx.recv() {
            eprintln!("coordinator: serving workers on {addr} (worker --connect http://{addr})");
        }
        if let Ok(addr) = dashboard_rx.recv() {
            eprintln!("coordinator: dashboard on http://{addr}/");
        }
    });
    let summary = run_job(&config, options).with_context(|| {
        if shutdown.load(Ordering::Relaxed) {
            format!("run '{}' stopped; continue it with --resume", config.name)
        } else {
            format!("run '{}' failed", config.name)
        }
    })?;
    let best = summary.best();
    let headline = config
        .scene
        .headline(&best.outcome)
        .unwrap_or_else(|| "-".into());
    println!(
        "{}: best {headline} at {} after {} evaluations in {:.1} s ({:?}); report in {}",
        config.name,
        summary.dims,
        summary.evaluations,
        summary.wall_seconds,
        summary.stop,
        config.run_dir().join("report.html").display()
    );
    if summary.unchanged_children > 0 {
        println!(
            "{} children made their dominant parent's design and were not evaluated (search.skip_unchanged)",
            summary.unchanged_children
        );
    }
    if summary.stop == amorph_coordinator::StopReason::Shutdown {
        println!("stopped before its budget: continue it with --resume");
    }
    Ok(())
}

/// `coordinator dashboard STORE`: serves the page from a run's store until Ctrl-C.
fn dashboard(store: &Path, listen: &str, token_file: Option<&Path>) -> anyhow::Result<()> {
    let token = amorph_coordinator::cluster::settings::shared_token(token_file, "--token-file")
        .map_err(anyhow::Error::msg)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    runtime.block_on(async {
        let bound = amorph_coordinator::dashboard::bind(listen, token).await?;
        let dashboard = bound.serve(store, None).await?;
        eprintln!(
            "coordinator: dashboard of {} on {} (Ctrl-C stops it)",
            store.display(),
            dashboard.url()
        );
        amorph_proto::signal::termination().await;
        dashboard.shutdown().await;
        Ok(())
    })
}

/// Ctrl-C or SIGTERM asks the run to stop; everything finished is already in the run store.
fn stop_on_signal(shutdown: Arc<AtomicBool>) {
    std::thread::spawn(move || {
        let Ok(rt) = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
        else {
            return;
        };
        rt.block_on(amorph_proto::signal::termination());
        eprintln!("coordinator: stopping (the run store keeps every finished evaluation)");
        shutdown.store(true, Ordering::Relaxed);
    });
}

fn health_check(url: &str) -> anyhow::Result<()> {
    use tonic_health::pb::health_check_response::ServingStatus;
    use tonic_health::pb::{HealthCheckRequest, health_client::HealthClient};
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    runtime.block_on(async {
        let channel = tonic::transport::Endpoint::from_shared(url.to_owned())?
            .connect_timeout(std::time::Duration::from_secs(2))
            .connect()
            .await
            .with_context(|| format!("cannot reach {url}"))?;
        let reply = HealthClient::new(channel)
            .check(HealthCheckRequest {
                service: "amorph.v1.EvaluationCoordinator".into(),
            })
            .await
            .with_context(|| format!("health check of {url}"))?
            .into_inner();
        anyhow::ensure!(
            reply.status == ServingStatus::Serving as i32,
            "{url} is not serving (status {})",
            reply.status
        );
        Ok(())
    })
}
