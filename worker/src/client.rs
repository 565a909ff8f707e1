//! `worker --connect URL`: the stateless gRPC worker. It registers, leases tasks up to its free
//! evaluation threads, evaluates them on the CPU pool, reports outcomes as they finish and
//! heartbeats. When the coordinator goes away it keeps what it finished and reconnects with
//! exponential backoff; on a stop signal it stops leasing, finishes or hands back its leases.
//!
//! A finished outcome is reported under the worker id its task was leased with, even after a
//! re-registration: the coordinator accepts a late report once, so a network cut never throws a
//! finished evaluation away.

use std::collections::HashMap;
use std::future::Future;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;

use amorph::task::Outcome;
use amorph::task::Scene;
use amorph_proto::ids::TaskId;
use amorph_proto::v1::evaluation_coordinator_client::EvaluationCoordinatorClient;
use amorph_proto::v1::{self, task_result};
use amorph_proto::{MAX_MESSAGE_BYTES, PROTOCOL_VERSION, convert};
use tokio::sync::{mpsc, watch};
use tonic::metadata::{Ascii, MetadataValue};
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::{Certificate, Channel, ClientTlsConfig, Endpoint};
use tonic::{Code, Request, Status};
use tracing::{debug, info, warn};

use crate::pool::{EvaluationMode, Job, JobDone, Pool};

/// How a worker connects and works.
#[derive(Clone, Debug)]
pub struct WorkerOptions {
    /// `http://host:port`, or `https://host:port` with TLS.
    pub url: String,
    /// Evaluations at once (its capacity).
    pub threads: usize,
    /// Threads that share one evaluation (1: each evaluation on its own thread). The outcome is
    /// the same bits for any count (`amorph::dynamics`); more pays where evaluations are fewer
    /// than cores, e.g. large robots or a batch smaller than the cluster.
    pub threads_per_evaluation: usize,
    /// Shown in the coordinator's logs and run store.
    pub name: String,
    /// The shared secret, if the coordinator requires one.
    pub token: Option<String>,
    /// PEM certificate of the authority that signed the coordinator's certificate (TLS).
    pub ca_cert: Option<PathBuf>,
    /// Name to check the coordinator's certificate against, if not the URL's host.
    pub tls_domain: Option<String>,
    pub mode: EvaluationMode,
    /// Longest wait between reconnection attempts.
    pub max_backoff: Duration,
    /// Give up after this long without reaching the coordinator (None: never).
    pub give_up_after: Option<Duration>,
    /// Exit once the coordinator says the run has finished (else wait for the next run).
    pub exit_when_finished: bool,
    /// On a stop signal, how long to let running evaluations finish before handing them back.
    pub grace: Duration,
    /// Bytes all evaluations at once may use (None: half the machine's memory); a task whose
    /// estimate exceeds its share (this divided by `threads`) is refused, not started.
    pub max_memory: Option<u64>,
}

/// Most evaluation threads a worker may run (the coordinator's largest capacity).
pub const MAX_THREADS: usize = 1024;

impl WorkerOptions {
    pub fn new(url: impl Into<String>, threads: usize) -> Self {
        Self {
            url: url.into(),
            threads: threads.max(1),
            threads_per_evaluation: 1,
            name: default_name(),
            token: None,
            ca_cert: None,
            tls_domain: None,
            mode: EvaluationMode::Physics,
            max_backoff: Duration::from_secs(10),
            give_up_after: None,
            exit_when_finished: true,
            grace: Duration::from_secs(30),
            max_memory: None,
        }
    }
}

fn default_name() -> String {
    let host = std::env::var("HOSTNAME")
        .ok()
        .or_else(|| std::fs::read_to_string("/etc/hostname").ok())
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "worker".into());
    format!("{host}:{}", std::process::id())
}

#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error("coordinator {url} refused this worker: {message}")]
    Refused { url: String, message: String },
    #[error("{0}")]
    Setup(String),
    #[error("coordinator {url} unreachable for {seconds:.0} s: {last}")]
    GaveUp {
        url: String,
        seconds: f64,
        last: String,
    },
}

/// What a worker did, for its exit line and tests.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WorkerSummary {
    pub evaluated: u64,
    pub reported: u64,
    pub duplicates: u64,
    pub released: u64,
    pub sessions: u64,
}

/// Metadata every call carries: the token.
#[derive(Clone, Debug)]
struct Auth {
    token: Option<MetadataValue<Ascii>>,
}

impl Interceptor for Auth {
    fn call(&mut self, mut request: Request<()>) -> Result<Request<()>, Status> {
        if let Some(token) = &self.token {
            request
                .metadata_mut()
                .insert(amorph_proto::AUTHORIZATION, token.clone());
        }
        Ok(request)
    }
}

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

fn endpoint(opts: &WorkerOptions) -> Result<Endpoint, ClientError> {
    let mut endpoint = Endpoint::from_shared(opts.url.clone())
        .map_err(|e| ClientError::Setup(format!("--connect {}: {e}", opts.url)))?
        .connect_timeout(Duration::from_secs(5))
        .tcp_nodelay(true)
        .http2_keep_alive_interval(Duration::from_secs(10))
        .keep_alive_timeout(Duration::from_secs(10));
    if opts.url.starts_with("https://") || opts.ca_cert.is_some() {
        let mut tls = ClientTlsConfig::new();
        if let Some(ca) = &opts.ca_cert {
            let pem = std::fs::read(ca)
                .map_err(|e| ClientError::Setup(format!("--ca {}: {e}", ca.display())))?;
            tls = tls.ca_certificate(Certificate::from_pem(pem));
        }
        if let Some(domain) = &opts.tls_domain {
            tls = tls.domain_name(domain.clone());
        }
        endpoint = endpoint
            .tls_config(tls)
            .map_err(|e| ClientError::Setup(format!("TLS for {}: {e}", opts.url)))?;
    }
    Ok(endpoint)
}

/// A refusal no retry can fix: wrong token, wrong protocol version, a request the coordinator
/// calls invalid.
fn is_fatal(status: &Status) -> bool {
    matches!(
        status.code(),
        Code::Unauthenticated
            | Code::PermissionDenied
            | Code::FailedPrecondition
            | Code::InvalidArgument
    )
}

impl Worker {
    fn free_slots(&self) -> u32 {
        self.pool.threads().saturating_sub(self.active.len()) as u32
    }

    async fn session(
        &mut self,
        stop: &mut watch::Receiver<bool>,
    ) -> Result<SessionEnd, SessionError> {
        let channel = self
            .endpoint
            .connect()
            .await
            .map_err(|e| SessionError::Retry(format!("connect: {e}")))?;
        let mut client = EvaluationCoordinatorClient::with_interceptor(channel, self.auth.clone())
            .max_decoding_message_size(MAX_MESSAGE_BYTES)
            .max_encoding_message_size(MAX_MESSAGE_BYTES);
        let registered = client
            .register(v1::RegisterRequest {
                protocol_version: PROTOCOL_VERSION,
                capacity: self.pool.threads() as u32,
                name: self.opts.name.clone(),
            })
            .await
            .map_err(|s| {
                if is_fatal(&s) {
                    SessionError::Fatal(ClientError::Refused {
                        url: self.opts.url.clone(),
                        message: format!("{:?}: {}", s.code(), s.message()),
                    })
                } else {
                    SessionError::Retry(format!("register: {}", s.message()))
                }
            })?
            .into_inner();
        let id = registered.worker_id;
        self.summary.sessions += 1;
        info!(worker = %id, url = %self.opts.url, threads = self.pool.threads(), "registered");
        let interval = Duration::from_millis(u64::from(registered.heartbeat_interval_ms.max(50)));
        let mut heartbeat = tokio::time::interval(interval);
        heartbeat.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut grace_deadline: Option<tokio::time::Instant> = None;
        let mut finished = false;
        let mut lease_call: Option<LeaseCall> = None;

        // What finished while the coordinator was away goes first.
        self.report(&mut client).await?;

        loop {
            if self.stopping && grace_deadline.is_none() {
                grace_deadline = Some(tokio::time::Instant::now() + self.opts.grace);
                info!(
                    active = self.active.len(),
                    "stopping: no new leases; finishing running evaluations"
                );
            }
            if self.stopping && self.active.is_empty() && self.unreported.is_empty() {
                return Ok(SessionEnd::Stopped);
            }
            if finished && self.active.is_empty() && self.unreported.is_empty() {
                return Ok(SessionEnd::RunFinished);
            }
            let want = if self.stopping || finished {
                0
            } else {
                self.free_slots()
            };
            // A lease call, once made, is always awaited to the end: dropping it could lose tasks
            // the coordinator already granted (they would sit leased to us until they expire).
            if lease_call.is_none() && want > 0 {
                let mut client = client.clone();
                let request = v1::LeaseRequest {
                    worker_id: id.clone(),
                    max_tasks: want,
                    wait_ms: 1000,
                };
                lease_call = Some(Box::pin(async move { client.lease(request).await }));
            }
            let lease = async {
                match lease_call.as_mut() {
                    Some(call) => call.await,
                    None => std::future::pending().await,
                }
            };
            let grace = async {
                match grace_deadline {
                    Some(d) => tokio::time::sleep_until(d).await,
                    None => std::future::pending().await,
                }
            };
            let event = tokio::select! {
                leased = lease => Event::Leased(leased),
                Some(done) = self.done.recv() => Event::Done(done),
                _ = heartbeat.tick() => Event::Heartbeat,
                changed = stop.changed() => Event::Stop(changed.is_err()),
                _ = grace => Event::GraceOver,
            };
            match event {
                Event::Leased(leased) => {
                    lease_call = None;
                    let leased = leased
                        .map_err(|s| self.call_failed("lease", s))?
                        .into_inner();
                    finished |= leased.run_finished;
                    for task in leased.tasks {
                        self.start(&mut client, &id, task).await?;
                    }
                    self.report(&mut client).await?;
                }
                Event::Done(done) => {
                    self.collect(done);
                    while let Ok(more) = self.done.try_recv() {
                        self.collect(more);
                    }
                    self.report(&mut client).await?;
                }
                Event::Heartbeat => {
                    let reply = client
                        .heartbeat(v1::HeartbeatRequest {
                            worker_id: id.clone(),
                            active_task_ids: wire_ids(&self.leased_under(&id)),
                            protocol_version: PROTOCOL_VERSION,
                        })
                        .await
                        .map_err(|s| self.call_failed("heartbeat", s))?
                        .into_inner();
                    finished |= reply.run_finished;
                    if !reply.revoked_task_ids.is_empty() {
                        debug!(tasks = ?reply.revoked_task_ids, "leases revoked; their outcomes will be reported late (accepted if still first)");
                    }
                }
                Event::Stop(closed) => self.stopping |= closed || *stop.borrow(),
                Event::GraceOver => {
                    let ours = self.leased_under(&id);
                    let released = client
                        .release(v1::ReleaseRequest {
                            worker_id: id.clone(),
                            task_ids: wire_ids(&ours),
                        })
                        .await
                        .map(|r| r.into_inner().released)
                        .unwrap_or(0);
                    for task in ours {
                        self.active.remove(&task);
                    }
                    self.summary.released += u64::from(released);
                    warn!(
                        released,
                        "grace period over: running evaluations handed back"
                    );
                    return Ok(SessionEnd::Stopped);
                }
            }
        }
    }

    fn leased_under(&self, id: &str) -> Vec<TaskId> {
        let mut ids: Vec<TaskId> = self
            .active
            .iter()
            .filter(|(_, lease)| lease.as_str() == id)
            .map(|(&t, _)| t)
            .collect();
        ids.sort_unstable();
        ids
    }

    fn call_failed(&self, call: &str, status: Status) -> SessionError {
        if is_fatal(&status) {
            SessionError::Fatal(ClientError::Refused {
                url: self.opts.url.clone(),
                message: format!("{call}: {:?}: {}", status.code(), status.message()),
            })
        } else {
            // Unavailable, a dropped connection, or NOT_FOUND for our id (the coordinator dropped
            // us or restarted): register again.
            SessionError::Retry(format!("{call}: {:?}: {}", status.code(), status.message()))
        }
    }

    /// Converts a leased task at the edge and puts it on the pool; a task that cannot be
    /// evaluated (malformed, scene unavailable) is reported as this worker's error for it.
    async fn start(
        &mut self,
        client: &mut Client,
        id: &str,
        task: v1::Task,
    ) -> Result<(), SessionError> {
        let task_id = TaskId(task.task_id);
        let scene = self.scene(client, id, &task.scene_id).await?;
        let converted = task
            .genome
            .as_ref()
            .ok_or_else(|| "task.genome is missing".to_owned())
            .and_then(|g| convert::genome_from_wire(g).map_err(|e| e.to_string()))
            .and_then(|genome| {
                convert::dims_from_wire(task.resolution.as_ref())
                    .map(|dims| (genome, dims))
                    .map_err(|e| e.to_string())
            })
            .and_then(|(genome, dims)| scene.map(|scene| (genome, dims, scene)))
            .and_then(|(genome, dims, scene)| {
                amorph::task::memory::check(&scene, dims, self.evaluation_budget)
                    .map(|()| (genome, dims, scene))
            });
        match converted {
            Ok((genome, dims, scene)) => {
                self.active.insert(task_id, id.to_owned());
                self.pool.submit(Job {
                    task_id,
                    genome,
                    scene,
                    dims,
                });
            }
            Err(error) => {
                warn!(task = %task_id, %error, "cannot evaluate a leased task");
                self.unreported.push(Finished {
                    lease_id: id.to_owned(),
                    task_id,
                    result: Err(error),
                    wall_seconds: 0.0,
                });
            }
        }
        Ok(())
    }

    /// The scene by id, from the cache or fetched once. `Err` inside is a task-level error.
    async fn scene(
        &mut self,
        client: &mut Client,
        id: &str,
        scene_id: &str,
    ) -> Result<Result<Arc<Scene>, String>, SessionError> {
        if let Some(scene) = self.scenes.get(scene_id) {
            return Ok(Ok(scene.clone()));
        }
        let reply = match client
            .fetch_scene(v1::FetchSceneRequest {
                worker_id: id.to_owned(),
                scene_id: scene_id.to_owned(),
            })
            .await
        {
            Ok(r) => r.into_inner(),
            Err(s) if s.code() == Code::NotFound => {
                return Ok(Err(format!("scene {scene_id}: {}", s.message())));
            }
            Err(s) => return Err(self.call_failed("fetch scene", s)),
        };
        match convert::scene_from_wire(&reply.scene_json) {
            Ok(scene) if convert::scene_id(&scene) == scene_id => {
                let scene = Arc::new(scene);
                self.scenes.insert(scene_id.to_owned(), scene.clone());
                Ok(Ok(scene))
            }
            Ok(_) => Ok(Err(format!(
                "scene {scene_id}: the fetched scene does not hash to its id"
            ))),
            Err(e) => Ok(Err(format!("scene {scene_id}: {e}"))),
        }
    }

    fn collect(&mut self, done: JobDone) {
        self.summary.evaluated += 1;
        // A task missing from `active` was handed back (release): its result is not ours to give.
        if let Some(lease_id) = self.active.remove(&done.task_id) {
            self.unreported.push(Finished {
                lease_id,
                task_id: done.task_id,
                result: Ok(done.outcome),
                wall_seconds: done.wall_seconds,
            });
        }
    }

    /// Reports everything finished, grouped by the worker id each task was leased under.
    async fn report(&mut self, client: &mut Client) -> Result<(), SessionError> {
        while !self.unreported.is_empty() {
            let lease_id = self.unreported[0].lease_id.clone();
            let (batch, rest): (Vec<Finished>, Vec<Finished>) =
                std::mem::take(&mut self.unreported)
                    .into_iter()
                    .partition(|f| f.lease_id == lease_id);
            self.unreported = rest;
            let results = batch
                .iter()
                .map(|f| v1::TaskResult {
                    task_id: f.task_id.0,
                    result: Some(match &f.result {
                        Ok(outcome) => {
                            task_result::Result::Outcome(convert::outcome_to_wire(outcome))
                        }
                        Err(error) => task_result::Result::Error(error.clone()),
                    }),
                    wall_seconds: f.wall_seconds,
                })
                .collect();
            match client
                .report(v1::ReportRequest {
                    worker_id: lease_id.clone(),
                    results,
                })
                .await
            {
                Ok(reply) => {
                    let reply = reply.into_inner();
                    self.summary.reported += batch.len() as u64;
                    self.summary.duplicates += reply
                        .dispositions
                        .iter()
                        .filter(|&&d| d == v1::ReportDisposition::Duplicate as i32)
                        .count() as u64;
                }
                // The coordinator no longer knows that lease (it restarted, or the tasks belong
                // to a finished run): nobody can use these outcomes.
                Err(s) if matches!(s.code(), Code::NotFound | Code::FailedPrecondition) => {
                    warn!(worker = %lease_id, tasks = batch.len(), reason = %s.message(), "outcomes refused by the coordinator: dropped");
                }
                Err(s) => {
                    // Keep them for the next session.
                    self.unreported.extend(batch);
                    return Err(self.call_failed("report", s));
                }
            }
        }
        Ok(())
    }
}

/// Task ids as the wire carries them.
fn wire_ids(ids: &[TaskId]) -> Vec<u64> {
    ids.iter().map(|id| id.0).collect()
}
