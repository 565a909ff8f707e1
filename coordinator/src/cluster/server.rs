//! Starts the coordinator's gRPC server: the evaluation service behind an optional shared-secret
//! check, the standard gRPC health service, optional TLS, explicit message size limits, and the
//! reaper that returns expired leases to the queue.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use amorph_proto::MAX_MESSAGE_BYTES;
use amorph_proto::v1::evaluation_coordinator_server::EvaluationCoordinatorServer;
use tokio::sync::watch;
use tokio::task::JoinHandle;
use tokio_stream::StreamExt;
use tokio_stream::wrappers::TcpListenerStream;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::{Identity, Server, ServerTlsConfig};
use tracing::{info, warn};

use super::connections::{ConnectionLimits, IDLE_TIMEOUT};
use super::credentials::{Authenticator, Credentials};
use super::queue::TaskQueue;
use super::service::CoordinatorService;

/// Concurrent calls on one connection: a worker needs three (a lease, a report, a heartbeat).
const MAX_STREAMS_PER_CONNECTION: u32 = 64;
const MAX_HEADER_BYTES: u32 = 16 << 10;
/// Longest any call may take, reading its request included.
const CALL_TIMEOUT: Duration = Duration::from_secs(30);

/// How the server listens and whom it lets in.
#[derive(Clone, Debug, Default)]
pub struct ServerOptions {
    /// Address to bind; port 0 picks a free one (see [`ServerHandle::addr`]).
    pub listen: String,
    /// Shared secret every call (but the health check) must carry as `authorization: Bearer …`,
    /// unless it carries one of `credentials`. All its holders are one principal.
    pub token: Option<String>,
    /// Per-worker credentials, each a principal of its own.
    pub credentials: Credentials,
    /// PEM certificate chain and private key: serve TLS instead of plain HTTP/2.
    pub tls: Option<(PathBuf, PathBuf)>,
    /// Take every worker's outcomes without a check (`cluster.verify = false`). The coordinator's
    /// own local workers never come through here: they are trusted by construction.
    pub trust_everyone: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    // The cause is the source, printed once by whoever prints the chain.
    #[error("cannot listen on {listen}")]
    Bind {
        listen: String,
        source: std::io::Error,
    },
    #[error("TLS: {0}")]
    Tls(String),
}

/// A running server; dropping it does not stop it, [`ServerHandle::shutdown`] does.
#[derive(Debug)]
pub struct ServerHandle {
    pub addr: SocketAddr,
    stop: watch::Sender<bool>,
    serve: JoinHandle<()>,
    reaper: JoinHandle<()>,
}

impl ServerHandle {
    /// `http://addr` or `https://addr`, for workers on this machine.
    pub fn url(&self, tls: bool) -> String {
        format!("{}://{}", if tls { "https" } else { "http" }, self.addr)
    }

    /// Stops accepting calls and waits for the server to wind down (at most a few seconds).
    pub async fn shutdown(self) {
        let _ = self.stop.send(true);
        self.reaper.abort();
        let _ = tokio::time::timeout(Duration::from_secs(5), self.serve).await;
    }
}

/// A PEM file, checked for its markers here: rustls would only say "transport error" later.
fn read_pem(path: &PathBuf, key: &str, markers: &[&str]) -> Result<Vec<u8>, ServerError> {
    let bytes = std::fs::read(path)
        .map_err(|e| ServerError::Tls(format!("{key} {}: {e}", path.display())))?;
    let text = String::from_utf8_lossy(&bytes);
    if !markers.iter().all(|m| text.contains(m)) {
        return Err(ServerError::Tls(format!(
            "{key} {}: not a PEM file (no {} line)",
            path.display(),
            markers.concat()
        )));
    }
    Ok(bytes)
}

/// Binds and starts serving on the current tokio runtime.
pub async fn start(
    options: &ServerOptions,
    queue: Arc<TaskQueue>,
    scene: &amorph::task::Scene,
) -> Result<ServerHandle, ServerError> {
    let listener = tokio::net::TcpListener::bind(&options.listen)
        .await
        .map_err(|source| ServerError::Bind {
            listen: options.listen.clone(),
            source,
        })?;
    let addr = listener.local_addr().map_err(|source| ServerError::Bind {
        listen: options.listen.clone(),
        source,
    })?;

    let service = EvaluationCoordinatorServer::new(CoordinatorService::new(
        queue.clone(),
        scene,
        options.trust_everyone,
    ))
    .max_decoding_message_size(MAX_MESSAGE_BYTES)
    .max_encoding_message_size(MAX_MESSAGE_BYTES);
    let limits = Arc::new(ConnectionLimits::new(
        queue.rules().max_workers_per_credential.saturating_mul(2),
    ));
    let hook_limits = limits.clone();
    let authenticator = Authenticator::new(options.token.as_deref(), options.credentials.clone())
        .on_authenticated(Arc::new(move |request, principal| {
            hook_limits.authenticated(request.remote_addr(), principal)
        }));
    let service = InterceptedService::new(service, authenticator);
    let (health, health_service) = tonic_health::server::health_reporter();
    health
        .set_service_status(
            "amorph.v1.EvaluationCoordinator",
            tonic_health::ServingStatus::Serving,
        )
        .await;
    health
        .set_service_status("", tonic_health::ServingStatus::Serving)
        .await;

    // Bounds on what one peer can hold open (docs/reference/protocol.md): streams per
    // connection, header size, and a deadline on every call (a lease waits at most 5 s, so an
    // honest call never comes near it) that also ends requests whose body never finishes.
    let mut builder = Server::builder()
        .tcp_nodelay(true)
        .http2_keepalive_interval(Some(Duration::from_secs(10)))
        .http2_keepalive_timeout(Some(Duration::from_secs(10)))
        .max_concurrent_streams(MAX_STREAMS_PER_CONNECTION)
        .http2_max_header_list_size(MAX_HEADER_BYTES)
        .timeout(CALL_TIMEOUT);
    if let Some((cert, key)) = &options.tls {
        let identity = Identity::from_pem(
            read_pem(cert, "cluster.tls_cert", &["-----BEGIN CERTIFICATE-----"])?,
            read_pem(key, "cluster.tls_key", &["-----BEGIN ", "PRIVATE KEY-----"])?,
        );
        builder = builder
            .tls_config(ServerTlsConfig::new().identity(identity))
            .map_err(|e| {
                let mut message = e.to_string();
                let mut cause = std::error::Error::source(&e);
                while let Some(c) = cause {
                    message = format!("{message}: {c}");
                    cause = c.source();
                }
                ServerError::Tls(format!(
                    "cluster.tls_cert and cluster.tls_key cannot be used ({message}): both must be PEM, the key the certificate's"
                ))
            })?;
    }
    // Honest workers send something every heartbeat interval.
    let idle = IDLE_TIMEOUT.max(queue.rules().heartbeat_interval * 3);
    let (stop, mut stopped) = watch::channel(false);
    let router = builder.add_service(health_service).add_service(service);
    let serve = tokio::spawn(async move {
        let shutdown = async move {
            let _ = stopped.wait_for(|s| *s).await;
        };
        // Serving a listener we bound ourselves bypasses the builder's TCP options: switch Nagle
        // off here, or a lease and a report in flight together stall on delayed ACKs. Then the
        // connection limits: a connection over them is dropped, that is closed, at once.
        let incoming = TcpListenerStream::new(listener).filter_map(move |stream| match stream {
            Ok(s) => {
                let _ = s.set_nodelay(true);
                limits.admit(s, idle).map(Ok)
            }
            Err(e) => Some(Err(e)),
        });
        if let Err(e) = router
            .serve_with_incoming_shutdown(incoming, shutdown)
            .await
        {
            warn!(error = %e, "gRPC server stopped with an error");
        }
    });

    let rules = queue.rules().clone();
    let tick = (rules.heartbeat_interval.min(rules.lease) / 4).max(Duration::from_millis(20));
    let reaper = tokio::spawn(async move {
        let mut interval = tokio::time::interval(tick);
        loop {
            interval.tick().await;
            queue.reap(std::time::Instant::now());
        }
    });
    info!(%addr, tls = options.tls.is_some(), token = options.token.is_some(), credentials = options.credentials.len(), "coordinator listening");
    Ok(ServerHandle {
        addr,
        stop,
        serve,
        reaper,
    })
}
