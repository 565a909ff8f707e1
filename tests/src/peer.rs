//! A raw gRPC peer for the hostile-peer tests: it speaks the protocol call by call, holding the
//! run's token (or a credential) as an attacker would, so each test can say exactly what it sends.

use std::time::{Duration, Instant};

use amorph_proto::v1::evaluation_coordinator_client::EvaluationCoordinatorClient;
use amorph_proto::v1::{self, task_result};
use amorph_proto::{PROTOCOL_VERSION, convert};
use tonic::metadata::{Ascii, MetadataValue};
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;
use tonic::{Request, Status};

/// Adds `authorization: Bearer <token>` to every call.
#[derive(Clone, Debug)]
pub struct Bearer(Option<MetadataValue<Ascii>>);

impl Interceptor for Bearer {
    fn call(&mut self, mut request: Request<()>) -> Result<Request<()>, Status> {
        if let Some(v) = &self.0 {
            request
                .metadata_mut()
                .insert(amorph_proto::AUTHORIZATION, v.clone());
        }
        Ok(request)
    }
}

pub type Client = EvaluationCoordinatorClient<InterceptedService<Channel, Bearer>>;

/// A client of the coordinator at `url`, presenting `token` if given.
pub async fn client(url: &str, token: Option<&str>) -> Client {
    let channel = tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .unwrap();
    let bearer = Bearer(token.map(|t| format!("Bearer {t}").parse().unwrap()));
    EvaluationCoordinatorClient::with_interceptor(channel, bearer)
        .max_encoding_message_size(2 * amorph_proto::MAX_MESSAGE_BYTES)
}

/// One registration: its client, id and session secret.
#[derive(Clone, Debug)]
pub struct Peer {
    pub client: Client,
    pub id: String,
    pub session: String,
}

impl Peer {
    /// Registers on `client` (the registration's calls share its connection).
    pub async fn register(client: &Client, capacity: u32, name: &str) -> Result<Peer, Status> {
        let mut client = client.clone();
        let r = client
            .register(v1::RegisterRequest {
                protocol_version: PROTOCOL_VERSION,
                capacity,
                name: name.into(),
            })
            .await?
            .into_inner();
        Ok(Peer {
            client,
            id: r.worker_id,
            session: r.session,
        })
    }

    /// This registration's id with another one's secret, or its own secret on another client.
    pub fn posing_as(&self, victim: &Peer) -> Peer {
        Peer {
            client: self.client.clone(),
            id: victim.id.clone(),
            session: self.session.clone(),
        }
    }

    pub async fn try_lease(&mut self, max: u32, wait_ms: u32) -> Result<Vec<v1::Task>, Status> {
        Ok(self
            .client
            .lease(v1::LeaseRequest {
                worker_id: self.id.clone(),
                session: self.session.clone(),
                max_tasks: max,
                wait_ms,
            })
            .await?
            .into_inner()
            .tasks)
    }

    /// Leases until `n` tasks are held (the first batch may not be queued yet): waits with the
    /// lease call's own long poll, never a blind sleep.
    pub async fn lease(&mut self, n: usize) -> Vec<v1::Task> {
        let start = Instant::now();
        let mut tasks = Vec::new();
        while tasks.len() < n {
            assert!(start.elapsed() < Duration::from_secs(60), "no work in 60 s");
            tasks.extend(
                self.try_lease((n - tasks.len()) as u32, 1000)
                    .await
                    .unwrap(),
            );
        }
        tasks
    }

    pub async fn report_all(
        &mut self,
        results: Vec<v1::TaskResult>,
    ) -> Result<v1::ReportResponse, Status> {
        Ok(self
            .client
            .report(v1::ReportRequest {
                worker_id: self.id.clone(),
                session: self.session.clone(),
                results,
            })
            .await?
            .into_inner())
    }

    pub async fn report(
        &mut self,
        task_id: u64,
        result: task_result::Result,
    ) -> Result<v1::ReportResponse, Status> {
        self.report_all(vec![v1::TaskResult {
            task_id,
            result: Some(result),
            wall_seconds: 0.0,
        }])
        .await
    }

    pub async fn heartbeat(&mut self, active: &[u64]) -> Result<v1::HeartbeatResponse, Status> {
        Ok(self
            .client
            .heartbeat(v1::HeartbeatRequest {
                worker_id: self.id.clone(),
                session: self.session.clone(),
                active_task_ids: active.to_vec(),
                protocol_version: PROTOCOL_VERSION,
            })
            .await?
            .into_inner())
    }

    pub async fn release(&mut self, ids: &[u64]) -> Result<u32, Status> {
        Ok(self
            .client
            .release(v1::ReleaseRequest {
                worker_id: self.id.clone(),
                session: self.session.clone(),
                task_ids: ids.to_vec(),
            })
            .await?
            .into_inner()
            .released)
    }

    /// The honest outcome of a leased task, computed here as a worker would.
    pub async fn evaluate(&mut self, task: &v1::Task) -> v1::Outcome {
        let scene = self
            .client
            .fetch_scene(v1::FetchSceneRequest {
                worker_id: String::new(),
                scene_id: task.scene_id.clone(),
            })
            .await
            .unwrap()
            .into_inner();
        let scene = convert::scene_from_wire(&scene.scene_json).unwrap();
        let genome = convert::genome_from_wire(task.genome.as_ref().unwrap()).unwrap();
        let dims = convert::dims_from_wire(task.resolution.as_ref()).unwrap();
        convert::outcome_to_wire(&scene.evaluate(&genome, dims))
    }

    /// Waits until the coordinator has dropped this registration as silent (and so re-queued its
    /// leases): `Release` answers NOT_FOUND then, and unlike every other call does not count as
    /// a sign of life.
    pub async fn wait_until_dropped(&mut self) {
        let start = Instant::now();
        loop {
            match self.release(&[]).await {
                Err(s) if s.code() == tonic::Code::NotFound => return,
                _ => assert!(start.elapsed() < Duration::from_secs(30), "never dropped"),
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }
}

/// A perfect beam: RMS error 0, metrics empty (the plausibility check refuses it).
pub fn forged() -> v1::Outcome {
    v1::Outcome {
        result: Some(v1::outcome::Result::Evaluated(v1::Evaluated {
            fitness: 0.0,
            metrics_json: b"{}".to_vec(),
        })),
    }
}

/// Another design's honest outcome where one differs: a forgery every number of which passes the
/// plausibility check.
pub fn swapped(truths: &[v1::Outcome], k: usize) -> v1::Outcome {
    truths
        .iter()
        .find(|t| **t != truths[k])
        .unwrap_or(&truths[k])
        .clone()
}

pub fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}
