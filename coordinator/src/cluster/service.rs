//! The gRPC face of the task queue: the `EvaluationCoordinator` service workers call. Everything a
//! peer sends is validated here before the queue sees it; every refusal is a status naming what
//! was wrong (`status.rs`), and none of them disturbs the run.

use std::sync::Arc;
use std::time::{Duration, Instant};

use amorph_proto::convert;
use amorph_proto::v1::evaluation_coordinator_server::EvaluationCoordinator;
use amorph_proto::v1::{self, task_result};
use tonic::{Request, Response, Status};
use tracing::warn;

use super::peer_text::{self, MAX_ERROR_CHARS, MAX_NAME_CHARS};
use super::queue::{Caller, Disposition, TaskQueue};
use super::status;
use amorph::task::Outcome;

use crate::ids::TaskId;
use crate::principal::Principal;

/// The principal the authenticator found for this call.
fn principal<T>(request: &Request<T>) -> Result<Principal, Status> {
    request
        .extensions()
        .get::<Principal>()
        .cloned()
        .ok_or_else(|| Status::unauthenticated("the call was not authenticated"))
}

/// Who makes a call, from its credential and the worker id and session it names.
fn caller(principal: Principal, worker_id: &str, session: &str) -> Result<Caller, Status> {
    Ok(Caller {
        worker: status::worker_id(worker_id)?,
        principal,
        session: session.to_owned(),
    })
}

/// Longest a lease call is held open waiting for work.
const MAX_LEASE_WAIT: Duration = Duration::from_secs(5);

#[derive(Debug)]
pub struct CoordinatorService {
    queue: Arc<TaskQueue>,
    /// The run's scene: every reported outcome is checked against what it can produce.
    scene: amorph::task::Scene,
    scene_id: String,
    scene_json: Vec<u8>,
    /// `cluster.verify = false`: every worker's outcomes are final without a check.
    trust_everyone: bool,
}

impl CoordinatorService {
    pub fn new(queue: Arc<TaskQueue>, scene: &amorph::task::Scene, trust_everyone: bool) -> Self {
        Self {
            queue,
            trust_everyone,
            scene: scene.clone(),
            scene_id: convert::scene_id(scene),
            scene_json: convert::scene_to_wire(scene),
        }
    }

    fn wire_task(&self, task: &crate::evaluator::Task) -> v1::Task {
        v1::Task {
            task_id: task.id.0,
            genome: Some(convert::genome_to_wire(&task.genome)),
            resolution: Some(convert::dims_to_wire(task.dims)),
            scene_id: self.scene_id.clone(),
            lease_ms: self
                .queue
                .rules()
                .lease
                .as_millis()
                .min(u128::from(u32::MAX)) as u32,
        }
    }
}

impl CoordinatorService {
    /// An outcome is a claim: refused (as malformed) unless the run's scene can produce it at
    /// the task's resolution (`Task::check_metrics`: the fitness and derived figures recomputed
    /// to the bit, the rest bounded by the physics). Before anything (a plot, a report, the
    /// search) consumes it.
    fn checked(&self, task: TaskId, outcome: Outcome) -> Result<Outcome, convert::WireError> {
        let Some(dims) = self.queue.task_dims(task) else {
            return Ok(outcome); // unknown or finished: the queue answers for it
        };
        self.scene.check_outcome(&outcome, dims).map_err(|claim| {
            convert::WireError::Malformed {
                field: "outcome.evaluated",
                message: claim.0,
            }
        })?;
        Ok(outcome)
    }
}

fn task_ids(ids: &[u64]) -> Vec<TaskId> {
    ids.iter().copied().map(TaskId).collect()
}

#[tonic::async_trait]
impl EvaluationCoordinator for CoordinatorService {
    async fn register(
        &self,
        request: Request<v1::RegisterRequest>,
    ) -> Result<Response<v1::RegisterResponse>, Status> {
        let peer = request.remote_addr();
        let principal = principal(&request)?;
        let trusted = self.trust_everyone;
        let r = request.into_inner();
        status::protocol_version(r.protocol_version).inspect_err(|_| {
            warn!(
                ?peer,
                version = r.protocol_version,
                "worker of another protocol version refused"
            );
        })?;
        status::capacity(r.capacity)?;
        let name = peer_text::clean(&r.name, MAX_NAME_CHARS);
        let name = match peer {
            Some(addr) => format!("{name} @{addr}"),
            None => name,
        };
        let registered =
            self.queue
                .register(&name, r.capacity, principal, trusted, Instant::now())?;
        Ok(Response::new(v1::RegisterResponse {
            worker_id: registered.worker.to_string(),
            heartbeat_interval_ms: self.queue.rules().heartbeat_interval.as_millis() as u32,
            session: registered.session,
            capacity: if trusted {
                r.capacity
            } else {
                r.capacity.min(self.queue.rules().max_capacity)
            },
        }))
    }

    async fn lease(
        &self,
        request: Request<v1::LeaseRequest>,
    ) -> Result<Response<v1::LeaseResponse>, Status> {
        let principal = principal(&request)?;
        let r = request.into_inner();
        let worker = caller(principal, &r.worker_id, &r.session)?;
        let wait = Duration::from_millis(u64::from(r.wait_ms)).min(MAX_LEASE_WAIT);
        let deadline = tokio::time::Instant::now() + wait;
        loop {
            // Enabled before looking at the queue, so a submit in between still wakes us.
            let notified = self.queue.work_notified();
            tokio::pin!(notified);
            notified.as_mut().enable();
            let (tasks, run_finished) = self.queue.lease(&worker, r.max_tasks, Instant::now())?;
            if !tasks.is_empty() || run_finished || tokio::time::Instant::now() >= deadline {
                return Ok(Response::new(v1::LeaseResponse {
                    tasks: tasks.iter().map(|t| self.wire_task(t)).collect(),
                    run_finished,
                }));
            }
            // On timeout the next turn takes one last look and returns, so an empty answer is
            // never stale.
            let _ = tokio::time::timeout_at(deadline, notified).await;
        }
    }

    async fn report(
        &self,
        request: Request<v1::ReportRequest>,
    ) -> Result<Response<v1::ReportResponse>, Status> {
        let principal = principal(&request)?;
        let r = request.into_inner();
        let caller = caller(principal, &r.worker_id, &r.session)?;
        let worker = caller.worker;
        status::list_length("results", r.results.len())?;
        // Every result is converted and checked first, then recorded in one call to the queue,
        // which proves the caller once. Every valid result is recorded even if another in the
        // same call is refused; the first refusal is returned after, so the worker learns of it.
        let mut malformed = Vec::with_capacity(r.results.len());
        let mut results = Vec::with_capacity(r.results.len());
        for result in r.results {
            let task = TaskId(result.task_id);
            let wall = if result.wall_seconds.is_finite() && result.wall_seconds >= 0.0 {
                result.wall_seconds
            } else {
                0.0
            };
            let (outcome, bad) = match result.result {
                Some(task_result::Result::Outcome(o)) => match convert::outcome_from_wire(&o)
                    .and_then(|outcome| self.checked(task, outcome))
                {
                    Ok(outcome) => (Ok(outcome), false),
                    Err(e) => (
                        Err(format!(
                            "malformed outcome: {}",
                            peer_text::clean(&e.to_string(), MAX_ERROR_CHARS)
                        )),
                        true,
                    ),
                },
                Some(task_result::Result::Error(e)) => {
                    (Err(peer_text::clean(&e, MAX_ERROR_CHARS)), false)
                }
                None => (Err("malformed report: result is missing".into()), true),
            };
            if bad {
                warn!(%worker, %task, "malformed outcome noted as the worker's error");
            }
            malformed.push(bad);
            results.push((task, outcome, wall));
        }
        let tasks: Vec<TaskId> = results.iter().map(|(task, _, _)| *task).collect();
        let recorded = self.queue.report_all(&caller, results, Instant::now())?;
        let mut dispositions = Vec::with_capacity(recorded.len());
        let mut refusal: Option<Status> = None;
        for ((d, bad), task) in recorded.into_iter().zip(malformed).zip(tasks) {
            match d {
                Ok(d) => dispositions.push(match (d, bad) {
                    (Disposition::Accepted, _) => v1::ReportDisposition::Accepted,
                    (Disposition::Duplicate, _) => v1::ReportDisposition::Duplicate,
                    (Disposition::ErrorNoted, true) => v1::ReportDisposition::Rejected,
                    (Disposition::ErrorNoted, false) => v1::ReportDisposition::ErrorNoted,
                } as i32),
                Err(e) => {
                    warn!(%worker, %task, error = %e, "report refused");
                    dispositions.push(v1::ReportDisposition::Unspecified as i32);
                    refusal.get_or_insert_with(|| e.into());
                }
            }
        }
        match refusal {
            Some(status) => Err(status),
            None => Ok(Response::new(v1::ReportResponse { dispositions })),
        }
    }

    async fn heartbeat(
        &self,
        request: Request<v1::HeartbeatRequest>,
    ) -> Result<Response<v1::HeartbeatResponse>, Status> {
        let principal = principal(&request)?;
        let r = request.into_inner();
        status::protocol_version(r.protocol_version)?;
        let worker = caller(principal, &r.worker_id, &r.session)?;
        status::list_length("active_task_ids", r.active_task_ids.len())?;
        let (revoked, run_finished) =
            self.queue
                .heartbeat(&worker, &task_ids(&r.active_task_ids), Instant::now())?;
        Ok(Response::new(v1::HeartbeatResponse {
            revoked_task_ids: revoked.into_iter().map(|t| t.0).collect(),
            run_finished,
        }))
    }

    async fn release(
        &self,
        request: Request<v1::ReleaseRequest>,
    ) -> Result<Response<v1::ReleaseResponse>, Status> {
        let principal = principal(&request)?;
        let r = request.into_inner();
        let worker = caller(principal, &r.worker_id, &r.session)?;
        status::list_length("task_ids", r.task_ids.len())?;
        let released = self.queue.release(&worker, &task_ids(&r.task_ids))?;
        Ok(Response::new(v1::ReleaseResponse { released }))
    }

    async fn fetch_scene(
        &self,
        request: Request<v1::FetchSceneRequest>,
    ) -> Result<Response<v1::FetchSceneResponse>, Status> {
        let r = request.into_inner();
        if r.scene_id != self.scene_id {
            return Err(status::unknown_scene(&r.scene_id));
        }
        Ok(Response::new(v1::FetchSceneResponse {
            scene_json: self.scene_json.clone(),
        }))
    }
}
