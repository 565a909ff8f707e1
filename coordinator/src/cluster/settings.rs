//! The `[cluster]` section of a run config as written ([`ClusterSection`]) and as used
//! ([`ClusterSettings`]: durations, counts and paths checked once, by `TryFrom`, with every bound
//! named by its key). Nothing here changes a run's result, so it may differ when a run is resumed.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::QueueRules;
use super::queue::MAX_WORKERS;
use super::status::MAX_CAPACITY;

/// Longest heartbeat interval, lease or worker timeout: a day. `Instant + Duration` panics on
/// overflow, so a config's `u64::MAX` ms must stop here.
const MAX_MS: u64 = 24 * 3600 * 1000;
/// Most local workers, threads per local worker, and attempts per task.
const MAX_LOCAL_WORKERS: usize = 1024;
const MAX_LOCAL_THREADS: usize = 1024;
const MAX_ATTEMPTS: u32 = 100;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClusterSection {
    /// Address workers connect to; port 0 picks a free one. 127.0.0.1 keeps the coordinator
    /// private to this machine; use 0.0.0.0:PORT (with a token) for workers on other machines.
    pub listen: String,
    /// Workers started inside the coordinator process, talking to it over loopback gRPC like any
    /// other worker. Unset: one per core. 0: only external `worker --connect` processes.
    pub local_workers: Option<usize>,
    /// Evaluation threads of each local worker.
    pub local_worker_threads: usize,
    /// Threads that share each local evaluation (1: one thread each). The outcome is the same bits
    /// for any count; with `local_workers` unset, the cores are divided by it.
    pub threads_per_evaluation: usize,
    /// File holding the shared secret workers must present (surrounding whitespace ignored). The
    /// AMORPH_TOKEN environment variable, if set, takes precedence. All its holders are one
    /// principal.
    pub token_file: Option<PathBuf>,
    /// Per-worker credentials (`coordinator credentials add NAME`): each is a principal of its
    /// own, so workers under different credentials check each other.
    pub credentials_file: Option<PathBuf>,
    /// PEM certificate chain and private key: serve TLS (workers connect with https://).
    pub tls_cert: Option<PathBuf>,
    pub tls_key: Option<PathBuf>,
    /// How often workers heartbeat, ms.
    pub heartbeat_ms: u64,
    /// How long a lease lasts without a heartbeat naming its task, ms.
    pub lease_ms: u64,
    /// A worker silent this long is dropped and its leases re-queued, ms.
    pub worker_timeout_ms: u64,
    /// Different workers whose errors mark a task failed instead of retried.
    pub max_attempts: u32,
    /// Longest a lease lives from its grant, heartbeats or not, ms; once evaluations are
    /// measured, a lease lives eight median evaluation times, within `[lease_ms, max_lease_ms]`.
    pub max_lease_ms: u64,
    /// Most tasks one outside worker holds at once, whatever capacity it declares.
    pub max_capacity: u32,
    /// Most outside workers registered at once under one credential (the shared token is one).
    pub max_workers_per_credential: usize,
    /// Which outside workers' outcomes are evaluated a second time elsewhere before they count
    /// (the coordinator's own local workers are trusted): see [`Verify`].
    pub verify: Verify,
}

/// `cluster.verify`: `true` (the default) checks an outside worker's outcome when it would change
/// a population; `"all"` checks every outside outcome, so that a worse outcome than the truth
/// cannot make a child lose either (about twice the evaluations); `false` trusts every worker.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Verify {
    Off,
    #[default]
    Decisive,
    All,
}

impl Serialize for Verify {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Verify::Off => s.serialize_bool(false),
            Verify::Decisive => s.serialize_bool(true),
            Verify::All => s.serialize_str("all"),
        }
    }
}

impl<'de> Deserialize<'de> for Verify {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Verify;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("cluster.verify: true, false or \"all\"")
            }
            fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<Verify, E> {
                Ok(if v { Verify::Decisive } else { Verify::Off })
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Verify, E> {
                match v {
                    "all" => Ok(Verify::All),
                    _ => Err(E::custom(format!(
                        "cluster.verify = {v:?}: expected true, false or \"all\""
                    ))),
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl Default for ClusterSection {
    fn default() -> Self {
        Self {
            listen: "127.0.0.1:0".into(),
            local_workers: None,
            local_worker_threads: 1,
            threads_per_evaluation: 1,
            token_file: None,
            credentials_file: None,
            tls_cert: None,
            tls_key: None,
            heartbeat_ms: 1000,
            lease_ms: 10_000,
            worker_timeout_ms: 5000,
            max_attempts: 3,
            max_lease_ms: 600_000,
            max_capacity: 256,
            max_workers_per_credential: 256,
            verify: Verify::Decisive,
        }
    }
}

impl ClusterSection {
    /// The shared secret: AMORPH_TOKEN, else the token file, else none.
    pub fn token(&self) -> Result<Option<String>, String> {
        shared_token(self.token_file.as_deref(), "cluster.token_file")
    }
}

/// The shared secret: AMORPH_TOKEN, else the contents of `file` (surrounding whitespace
/// ignored; an empty file is an error), else none. `named` names the file's setting in messages.
pub fn shared_token(file: Option<&Path>, named: &str) -> Result<Option<String>, String> {
    if let Ok(token) = std::env::var("AMORPH_TOKEN")
        && !token.trim().is_empty()
    {
        return Ok(Some(token.trim().to_owned()));
    }
    let Some(path) = file else {
        return Ok(None);
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("{named} {}: {e}", path.display()))?;
    let token = text.trim();
    if token.is_empty() {
        return Err(format!("{named} {} is empty", path.display()));
    }
    Ok(Some(token.to_owned()))
}

/// The `[cluster]` section, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusterSettings {
    pub listen: String,
    /// Local workers to start (one per core when the config leaves it unset).
    pub local_workers: usize,
    pub local_worker_threads: usize,
    pub threads_per_evaluation: usize,
    /// PEM certificate chain and private key.
    pub tls: Option<(PathBuf, PathBuf)>,
    pub rules: QueueRules,
    pub verify: Verify,
}

/// `cluster.<key>` in milliseconds, between `min` and a day.
fn millis(key: &str, ms: u64, min: u64) -> Result<Duration, String> {
    if !(min..=MAX_MS).contains(&ms) {
        return Err(format!(
            "cluster.{key} = {ms} must be between {min} and {MAX_MS} (a day)"
        ));
    }
    Ok(Duration::from_millis(ms))
}

fn count(key: &str, n: usize, min: usize, max: usize) -> Result<usize, String> {
    if !(min..=max).contains(&n) {
        return Err(format!(
            "cluster.{key} = {n} must be between {min} and {max}"
        ));
    }
    Ok(n)
}

impl TryFrom<&ClusterSection> for ClusterSettings {
    type Error = String;

    fn try_from(c: &ClusterSection) -> Result<Self, String> {
        if c.listen.parse::<std::net::SocketAddr>().is_err()
            && !c
                .listen
                .rsplit_once(':')
                .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok())
        {
            return Err(format!("cluster.listen = {:?} is not HOST:PORT", c.listen));
        }
        let threads_per_evaluation = count(
            "threads_per_evaluation",
            c.threads_per_evaluation,
            1,
            MAX_LOCAL_THREADS,
        )?;
        let local_workers = match c.local_workers {
            Some(n) => count("local_workers", n, 0, MAX_LOCAL_WORKERS)?,
            None => (std::thread::available_parallelism().map_or(1, |n| n.get())
                / threads_per_evaluation)
                .clamp(1, MAX_LOCAL_WORKERS),
        };
        let local_worker_threads = count(
            "local_worker_threads",
            c.local_worker_threads,
            1,
            MAX_LOCAL_THREADS,
        )?;
        let tls = match (&c.tls_cert, &c.tls_key) {
            (Some(cert), Some(key)) => Some((cert.clone(), key.clone())),
            (None, None) => None,
            _ => {
                return Err(
                    "cluster.tls_cert and cluster.tls_key go together: set both or neither".into(),
                );
            }
        };
        let heartbeat_interval = millis("heartbeat_ms", c.heartbeat_ms, 10)?;
        let lease = millis("lease_ms", c.lease_ms, 10)?;
        let worker_timeout = millis("worker_timeout_ms", c.worker_timeout_ms, 10)?;
        if lease <= heartbeat_interval {
            return Err("cluster.lease_ms must be longer than cluster.heartbeat_ms".into());
        }
        if worker_timeout <= heartbeat_interval {
            return Err(
                "cluster.worker_timeout_ms must be longer than cluster.heartbeat_ms".into(),
            );
        }
        let max_lease = millis("max_lease_ms", c.max_lease_ms, c.lease_ms)?;
        if !(1..=MAX_ATTEMPTS).contains(&c.max_attempts) {
            return Err(format!(
                "cluster.max_attempts = {} must be between 1 and {MAX_ATTEMPTS}",
                c.max_attempts
            ));
        }
        Ok(Self {
            listen: c.listen.clone(),
            local_workers,
            local_worker_threads,
            threads_per_evaluation,
            tls,
            rules: QueueRules {
                lease,
                heartbeat_interval,
                worker_timeout,
                max_attempts: c.max_attempts,
                max_lease,
                max_capacity: count(
                    "max_capacity",
                    c.max_capacity as usize,
                    1,
                    MAX_CAPACITY as usize,
                )? as u32,
                max_workers_per_credential: count(
                    "max_workers_per_credential",
                    c.max_workers_per_credential,
                    1,
                    MAX_WORKERS,
                )?,
            },
            verify: c.verify,
        })
    }
}

#[cfg(test)]
mod tests;
