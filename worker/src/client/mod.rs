//! `worker --connect URL`: the stateless gRPC worker. It registers, leases tasks up to its free
//! evaluation threads, evaluates them on the CPU pool, reports outcomes as they finish and
//! heartbeats. When the coordinator goes away it keeps what it finished and reconnects with
//! exponential backoff; on a stop signal it stops leasing, finishes or hands back its leases.
//!
//! A finished outcome is reported under the worker id its task was leased with, even after a
//! re-registration: the coordinator accepts a late report once, so a network cut never throws a
//! finished evaluation away.
//!
//! Files: `options` (what a worker is told and what it reports), `connection` (reaching the
//! coordinator: TLS, the token, which refusals are final), `session` (one connection's lease,
//! evaluate and report loop).

use std::collections::HashMap;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;

use amorph::task::Outcome;
use amorph::task::Scene;
use amorph_proto::ids::TaskId;
use amorph_proto::v1::evaluation_coordinator_client::EvaluationCoordinatorClient;
use amorph_proto::v1::{self};
use tokio::sync::{mpsc, watch};
use tonic::Status;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::{Channel, Endpoint};
use tracing::warn;

use crate::pool::{JobDone, Pool};

mod connection;
mod options;
mod session;

use connection::{Auth, endpoint};
pub use options::{ClientError, MAX_THREADS, WorkerOptions, WorkerSummary};

type Client = EvaluationCoordinatorClient<InterceptedService<Channel, Auth>>;
type LeaseCall =
    Pin<Box<dyn Future<Output = Result<tonic::Response<v1::LeaseResponse>, Status>> + Send>>;

/// A result waiting to be reported, with the worker id its task was leased under.
#[derive(Debug)]
struct Finished {
    lease_id: String,
    task_id: TaskId,
    result: Result<Outcome, String>,
    wall_seconds: f64,
}

/// Everything that survives a reconnection.
struct Worker {
    opts: WorkerOptions,
    endpoint: Endpoint,
    auth: Auth,
    pool: Pool,
    /// Bytes one evaluation may use.
    evaluation_budget: u64,
    done: mpsc::UnboundedReceiver<JobDone>,
    /// Tasks on the pool, with the worker id they were leased under.
    active: HashMap<TaskId, String>,
    unreported: Vec<Finished>,
    /// The session secret of each worker id this process registered as.
    sessions: HashMap<String, String>,
    scenes: HashMap<String, Arc<Scene>>,
    stopping: bool,
    summary: WorkerSummary,
}

enum Event {
    Leased(Result<tonic::Response<v1::LeaseResponse>, Status>),
    Done(JobDone),
    Heartbeat,
    Stop(bool),
    GraceOver,
}

enum SessionEnd {
    RunFinished,
    Stopped,
}

/// Why a session ended early: reconnect, or give up for good.
enum SessionError {
    Retry(String),
    Fatal(ClientError),
}

/// Runs a worker until the run finishes (if `exit_when_finished`), a stop is requested, or the
/// coordinator refuses it.
pub async fn run_worker(
    opts: WorkerOptions,
    mut stop: watch::Receiver<bool>,
) -> Result<WorkerSummary, ClientError> {
    let endpoint = endpoint(&opts)?;
    let auth = Auth {
        token: opts
            .token
            .as_deref()
            .map(|t| {
                format!("Bearer {t}")
                    .parse()
                    .map_err(|_| ClientError::Setup("the token must be printable ASCII".into()))
            })
            .transpose()?,
    };
    if opts.threads > MAX_THREADS {
        return Err(ClientError::Setup(format!(
            "--threads {}: at most {MAX_THREADS}",
            opts.threads
        )));
    }
    let (done_tx, done) = mpsc::unbounded_channel();
    let pool = Pool::new(
        opts.threads,
        opts.threads_per_evaluation,
        opts.mode,
        done_tx,
    )
    .map_err(|e| {
        ClientError::Setup(format!(
            "starting {} evaluation threads of {} each: {e}",
            opts.threads, opts.threads_per_evaluation
        ))
    })?;
    let mut worker = Worker {
        evaluation_budget: opts
            .max_memory
            .unwrap_or_else(amorph::task::memory::default_budget)
            / opts.threads as u64,
        pool,
        opts,
        endpoint,
        auth,
        done,
        active: HashMap::new(),
        unreported: Vec::new(),
        sessions: HashMap::new(),
        scenes: HashMap::new(),
        stopping: false,
        summary: WorkerSummary::default(),
    };
    let mut backoff = Duration::from_millis(100);
    let mut unreachable_since: Option<tokio::time::Instant> = None;
    loop {
        if *stop.borrow() {
            worker.stopping = true;
        }
        match worker.session(&mut stop).await {
            Ok(SessionEnd::Stopped) => return Ok(worker.summary),
            Ok(SessionEnd::RunFinished) if worker.opts.exit_when_finished => {
                return Ok(worker.summary);
            }
            Ok(SessionEnd::RunFinished) => {
                backoff = Duration::from_millis(100);
                unreachable_since = None;
                sleep_or_stop(Duration::from_secs(1), &mut stop).await;
            }
            Err(SessionError::Fatal(e)) => return Err(e),
            Err(SessionError::Retry(reason)) => {
                if worker.stopping && worker.active.is_empty() && worker.unreported.is_empty() {
                    return Ok(worker.summary);
                }
                let since = *unreachable_since.get_or_insert_with(tokio::time::Instant::now);
                if let Some(limit) = worker.opts.give_up_after
                    && since.elapsed() >= limit
                {
                    return Err(ClientError::GaveUp {
                        url: worker.opts.url.clone(),
                        seconds: since.elapsed().as_secs_f64(),
                        last: reason,
                    });
                }
                warn!(url = %worker.opts.url, %reason, retry_in_ms = backoff.as_millis() as u64, "coordinator unreachable: reconnecting");
                sleep_or_stop(backoff, &mut stop).await;
                backoff = (backoff * 2).min(worker.opts.max_backoff);
                continue;
            }
        }
    }
}

async fn sleep_or_stop(duration: Duration, stop: &mut watch::Receiver<bool>) {
    tokio::select! {
        _ = tokio::time::sleep(duration) => {}
        _ = stop.changed() => {}
    }
}

/// Task ids as the wire carries them.
fn wire_ids(ids: &[TaskId]) -> Vec<u64> {
    ids.iter().map(|id| id.0).collect()
}
