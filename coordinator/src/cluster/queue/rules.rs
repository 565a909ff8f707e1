//! The queue's vocabulary: its timing and retry rules, what a report did, why a call was
//! refused, and the counts it keeps.

use std::time::Duration;

use crate::ids::{TaskId, WorkerId};

/// Timing and retry rules of the queue.
#[derive(Clone, Debug, PartialEq)]
pub struct QueueRules {
    /// How long a lease lasts without a heartbeat naming its task.
    pub lease: Duration,
    /// How often workers are asked to heartbeat.
    pub heartbeat_interval: Duration,
    /// A worker silent this long is dropped and its leases go back to the queue.
    pub worker_timeout: Duration,
    /// Different workers whose errors mark a task failed rather than retried.
    pub max_attempts: u32,
    /// Longest a lease lives from its grant, heartbeats or not, so a worker that names its
    /// leases in every heartbeat cannot keep them for ever. Once evaluations have been measured
    /// the lifetime follows them (`share.rs`), within `[lease, max_lease]`. A lease that runs out
    /// goes to another worker; the first holder's outcome still counts if it comes first.
    pub max_lease: Duration,
    /// Most tasks one outside worker may hold, whatever capacity it declares.
    pub max_capacity: u32,
    /// Most outside workers registered at once under one credential (the shared token counts as
    /// one).
    pub max_workers_per_credential: usize,
}

impl Default for QueueRules {
    fn default() -> Self {
        Self {
            lease: Duration::from_secs(30),
            heartbeat_interval: Duration::from_secs(1),
            worker_timeout: Duration::from_secs(5),
            max_attempts: 3,
            max_lease: Duration::from_secs(600),
            max_capacity: 256,
            max_workers_per_credential: 256,
        }
    }
}

/// Most outside workers registered at once.
pub const MAX_WORKERS: usize = 4096;

/// What a report did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Disposition {
    Accepted,
    Duplicate,
    ErrorNoted,
}

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum QueueError {
    #[error("worker {0} is not registered (register again)")]
    UnknownWorker(WorkerId),
    #[error("task {0} does not exist")]
    UnknownTask(TaskId),
    #[error("{task} was never leased to worker {worker}")]
    NotLeasedTo { task: TaskId, worker: WorkerId },
    #[error(
        "worker {0} is quarantined: an outcome it or its credential reported disagreed with a check"
    )]
    Quarantined(WorkerId),
    #[error("{MAX_WORKERS} outside workers are registered: try again once some have left")]
    TooManyWorkers,
    #[error(
        "{principal} has {limit} workers registered, none idle (cluster.max_workers_per_credential)"
    )]
    TooManyForCredential { principal: String, limit: usize },
    #[error("the session secret does not match worker {0} and this credential")]
    BadSession(WorkerId),
}

/// Counts for progress lines and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QueueStats {
    pub workers: usize,
    pub queued: usize,
    pub leased: usize,
    pub dispatched: u64,
    pub completed: u64,
    pub duplicates: u64,
    pub worker_errors: u64,
    pub expired_leases: u64,
    /// Idle registrations dropped to make room for a new one of the same credential.
    pub evicted: u64,
}

/// A worker's error for a task, for the run store: (task, worker, message).
pub type NotedError = (TaskId, WorkerId, String);
