//! The whole coordinator job, as `coordinator --config` runs it: open (or resume) the run store,
//! serve workers over gRPC, start the local workers, run the search on the cluster, then wind
//! everything down. The tests drive the very same function.

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use amorph::dynamics::EvaluationThreads;
use amorph::task::memory;
use tokio::sync::watch;
use tokio::task::JoinHandle;
use tracing::{info, warn};

use crate::cluster::credentials::Credentials;
use crate::cluster::local::{LocalSummary, LocalWorker};
use crate::cluster::queue::QueueError;
use crate::cluster::server::ServerHandle;
use crate::cluster::{self, ClusterEvaluator, ClusterSettings, ServerOptions, TaskQueue, Verify};
use crate::config::RunConfig;
use crate::dashboard::{self, Dashboard};
use crate::progress::Progress;
use crate::run::{RunContext, RunError, run};
use crate::store::{RunStore, StoreError};
use crate::summary::{RunSummary, StopReason};

/// How to start a run store.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StoreMode {
    /// A new run; an existing store is an error.
    #[default]
    New,
    /// A new run, deleting an existing store.
    Fresh,
    /// Continue the run in the existing store.
    Resume,
}

/// Everything about a job that is not in its config.
#[derive(Debug)]
pub struct JobOptions {
    pub store: StoreMode,
    /// Overrides `cluster.listen`.
    pub listen: Option<String>,
    /// Overrides `cluster.local_workers`.
    pub local_workers: Option<usize>,
    /// Overrides the token from AMORPH_TOKEN / `cluster.token_file` (tests).
    pub token: Option<String>,
    pub progress: Progress,
    /// Set to stop the run (Ctrl-C): it stops mid-batch, keeping every finished evaluation.
    pub shutdown: Arc<AtomicBool>,
    /// Told the server's address once it listens (before the first task is queued).
    pub on_listening: Option<std::sync::mpsc::Sender<SocketAddr>>,
    /// Overrides `dashboard.listen`: where to serve the live dashboard.
    pub dashboard: Option<String>,
    /// Told the dashboard's address once it is served.
    pub on_dashboard: Option<std::sync::mpsc::Sender<SocketAddr>>,
}

impl Default for JobOptions {
    fn default() -> Self {
        Self {
            store: StoreMode::New,
            listen: None,
            local_workers: None,
            token: None,
            progress: Progress::hidden(),
            shutdown: Arc::new(AtomicBool::new(false)),
            on_listening: None,
            dashboard: None,
            on_dashboard: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error(transparent)]
    Store(#[from] StoreError),
    #[error(transparent)]
    Server(#[from] cluster::server::ServerError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error("config {path}: {message}")]
    Config { path: String, message: String },
    #[error("cannot start the async runtime: {0}")]
    Runtime(std::io::Error),
    #[error(transparent)]
    Dashboard(#[from] crate::dashboard::DashboardError),
}

/// Runs a config on the cluster: the coordinator's gRPC server, `local_workers` in-process workers
/// and any `worker --connect` processes that join.
pub fn run_job(config: &RunConfig, options: JobOptions) -> Result<RunSummary, JobError> {
    let mut coordinator = Coordinator::start(config, &options)?;
    let ctx = RunContext {
        store: &coordinator.store,
        shutdown: &options.shutdown,
        progress: &options.progress,
    };
    let result = run(config, &mut coordinator.evaluator, &ctx);
    // Only a run that ended tells workers it finished (so they exit): after a stop or a failure
    // the run is not over, and external workers should wait to serve its resumption. A run
    // stopped at an epoch boundary returns Ok with `StopReason::Shutdown`: not finished either.
    let finished = result
        .as_ref()
        .is_ok_and(|summary| summary.stop != StopReason::Shutdown);
    coordinator.close(finished);
    Ok(result?)
}

/// A coordinator at work: its gRPC server listening, its local workers pulling tasks, its run
/// store open, and the evaluator that hands tasks to all of them. [`run_job`] runs a search on
/// it; [`crate::asked::AskedRun`] evaluates batches a caller outside the search asks for.
#[derive(Debug)]
pub struct Coordinator {
    pub store: RunStore,
    pub evaluator: ClusterEvaluator,
    /// Where workers connect: `http://HOST:PORT`, or `https://` with TLS.
    pub url: String,
    runtime: tokio::runtime::Runtime,
    server: ServerHandle,
    queue: Arc<TaskQueue>,
    workers: Vec<JoinHandle<Result<LocalSummary, QueueError>>>,
    stop_workers: watch::Sender<bool>,
    shutdown: Arc<AtomicBool>,
    dashboard: Option<Dashboard>,
}

impl Coordinator {
    /// Listens, opens (or resumes) the run store and starts the local workers.
    pub fn start(config: &RunConfig, options: &JobOptions) -> Result<Self, JobError> {
        let config_error = |message: String| JobError::Config {
            path: config.source.display().to_string(),
            message,
        };
        // Command-line overrides are checked by the same bounds as the config's keys.
        let mut section = config.cluster.clone();
        if let Some(listen) = &options.listen {
            section.listen = listen.clone();
        }
        if let Some(n) = options.local_workers {
            section.local_workers = Some(n);
        }
        let settings = ClusterSettings::try_from(&section).map_err(config_error)?;
        let token = match options.token.clone() {
            Some(t) => Some(t),
            None => section.token().map_err(config_error)?,
        };
        let credentials = match &section.credentials_file {
            Some(path) => Credentials::load(path).map_err(|e| config_error(e.to_string()))?,
            None => Credentials::default(),
        };
        // The network side needs little CPU: two runtime threads leave the cores to the evaluations.
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("coordinator-io")
            .enable_all()
            .build()
            .map_err(JobError::Runtime)?;

        // Listen before touching the run store, so a port in use leaves no store behind to demand
        // --resume or --fresh on the retry.
        let queue = Arc::new(TaskQueue::new(settings.rules.clone()));
        let server_options = ServerOptions {
            listen: settings.listen.clone(),
            token: token.clone(),
            credentials,
            tls: settings.tls.clone(),
            trust_everyone: settings.verify == Verify::Off,
        };
        let server = runtime.block_on(cluster::start(
            &server_options,
            queue.clone(),
            &config.scene,
        ))?;
        let dashboard = match options
            .dashboard
            .as_ref()
            .or(config.dashboard.listen.as_ref())
        {
            None => None,
            Some(listen) => match runtime.block_on(dashboard::bind(listen, token.clone())) {
                Ok(bound) => Some(bound),
                Err(e) => {
                    runtime.block_on(server.shutdown());
                    return Err(e.into());
                }
            },
        };
        let store = match options.store {
            StoreMode::New => RunStore::create(config, false),
            StoreMode::Fresh => RunStore::create(config, true),
            StoreMode::Resume => RunStore::resume(config),
        };
        let store = match store {
            Ok(store) => store,
            Err(e) => {
                runtime.block_on(server.shutdown());
                return Err(e.into());
            }
        };
        let url = server.url(server_options.tls.is_some());
        if let Some(tx) = &options.on_listening {
            let _ = tx.send(server.addr);
        }
        let dashboard = match dashboard {
            None => None,
            Some(bound) => match runtime.block_on(bound.serve(store.path(), Some(queue.clone()))) {
                Ok(dashboard) => {
                    if let Some(tx) = &options.on_dashboard {
                        let _ = tx.send(dashboard.addr);
                    }
                    info!(url = %dashboard.url(), "dashboard served");
                    Some(dashboard)
                }
                Err(e) => {
                    runtime.block_on(server.shutdown());
                    return Err(e.into());
                }
            },
        };

        let (stop_workers, stop_rx) = watch::channel(false);
        let local = settings.local_workers;
        let scene = Arc::new(config.scene.clone());
        // The local workers share this machine: each gets its part of the default budget.
        let budget = memory::default_budget() / local.max(1) as u64;
        let mut workers = Vec::with_capacity(local);
        for i in 0..local {
            let threads = EvaluationThreads::new(settings.threads_per_evaluation, move |j| {
                format!("local-{i}.{j}")
            })
            .map_err(|e| JobError::Runtime(std::io::Error::other(e)))?;
            let worker = LocalWorker::new(
                queue.clone(),
                scene.clone(),
                format!("local-{i}"),
                settings.local_worker_threads,
                budget,
            )
            .sharing_evaluations(threads);
            workers.push(runtime.spawn(worker.run(stop_rx.clone())));
        }
        info!(%url, local_workers = local, store = %store.path().display(), "coordinator ready");

        let evaluator = ClusterEvaluator::new(queue.clone(), options.shutdown.clone(), scene)
            .checking_every_claim(settings.verify == Verify::All);
        Ok(Self {
            store,
            evaluator,
            url,
            runtime,
            server,
            queue,
            workers,
            stop_workers,
            shutdown: options.shutdown.clone(),
            dashboard,
        })
    }

    /// Winds everything down. `finished` tells outside workers the run is over, so they exit;
    /// otherwise they wait to serve its resumption.
    pub fn close(self, finished: bool) {
        let checks = self.evaluator.check_stats();
        if checks.checks > 0 {
            info!(
                checks = checks.checks,
                by_coordinator = checks.by_coordinator,
                disagreements = checks.disagreements,
                "verification: outside workers' outcomes checked by a second evaluation"
            );
        }
        if finished {
            self.queue.finish();
        }
        let _ = self.stop_workers.send(true);
        let (queue, shutdown, server) = (self.queue, self.shutdown, self.server);
        let (workers, dashboard) = (self.workers, self.dashboard);
        self.runtime.block_on(async {
            if let Some(dashboard) = dashboard {
                dashboard.shutdown().await;
            }
            for worker in workers {
                match tokio::time::timeout(Duration::from_secs(3), worker).await {
                    Ok(Ok(Ok(_))) => {}
                    Ok(Ok(Err(e))) => warn!(error = %e, "local worker ended with an error"),
                    Ok(Err(e)) => warn!(error = %e, "local worker panicked"),
                    Err(_) => warn!("local worker did not stop in time"),
                }
            }
            if finished {
                farewell(&queue, &shutdown).await;
            }
            server.shutdown().await;
        });
        self.runtime.shutdown_timeout(Duration::from_secs(1));
    }
}

/// Keeps serving until every outside worker has heard that the run finished, so it exits rather
/// than retrying a closed port (and, with `give_up_after`, failing). A worker between two calls
/// hears it on its next heartbeat; one that never calls again is dropped by the reaper after
/// `worker_timeout`, which bounds the wait. Ctrl-C ends it at once.
async fn farewell(queue: &TaskQueue, shutdown: &AtomicBool) {
    let rules = queue.rules();
    let deadline = tokio::time::Instant::now() + rules.worker_timeout + rules.heartbeat_interval;
    let poll = (rules.heartbeat_interval / 4).max(Duration::from_millis(10));
    while !queue.everyone_told()
        && !shutdown.load(Ordering::Relaxed)
        && tokio::time::Instant::now() < deadline
    {
        tokio::time::sleep(poll).await;
    }
}
