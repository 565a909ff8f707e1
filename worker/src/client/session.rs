//! One session: a connection's lease, evaluate and report loop, and what a worker keeps when
//! the connection goes.

use std::sync::Arc;
use std::time::Duration;

use amorph::task::Scene;
use amorph_proto::ids::TaskId;
use amorph_proto::v1::evaluation_coordinator_client::EvaluationCoordinatorClient;
use amorph_proto::v1::{self, task_result};
use amorph_proto::{MAX_MESSAGE_BYTES, PROTOCOL_VERSION, convert};
use tokio::sync::watch;
use tonic::{Code, Status};
use tracing::{debug, info, warn};

use crate::pool::{Job, JobDone};

use super::connection::is_fatal;
use super::{
    Client, ClientError, Event, Finished, LeaseCall, SessionEnd, SessionError, Worker, wire_ids,
};

impl Worker {
    fn free_slots(&self) -> u32 {
        self.pool.threads().saturating_sub(self.active.len()) as u32
    }

    pub(super) async fn session(
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
        let session = registered.session;
        // Earlier registrations matter only while a result leased under them waits.
        let (active, unreported) = (&self.active, &self.unreported);
        self.sessions.retain(|old, _| {
            active.values().any(|l| l == old) || unreported.iter().any(|f| &f.lease_id == old)
        });
        self.sessions.insert(id.clone(), session.clone());
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
                    session: session.clone(),
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
                            session: session.clone(),
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
                            session: session.clone(),
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
                    .map_err(|e| e.to_string())
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
                    session: self.sessions.get(&lease_id).cloned().unwrap_or_default(),
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
