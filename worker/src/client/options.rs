//! What a worker is told (`WorkerOptions`), how it fails for good (`ClientError`), and what it
//! did (`WorkerSummary`).

use std::path::PathBuf;
use std::time::Duration;

use crate::pool::EvaluationMode;

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
