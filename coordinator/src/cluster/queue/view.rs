//! What the queue shows a watcher (the dashboard): each registered worker as it stands now. Read
//! under the queue's lock and copied out, so a watcher never holds it.

use std::time::Instant;

use serde::Serialize;

use super::TaskQueue;

/// One registered worker, as the dashboard lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorkerView {
    /// `name (id)`: the name the worker gave (with ` @address` for a remote one) and the id this
    /// coordinator issued; the run store's `evaluation.worker` names it the same way.
    pub label: String,
    /// The principal behind it: `this coordinator`, `the shared token` or `credential NAME`.
    pub principal: String,
    /// Evaluations it runs at once (its registration's capacity).
    pub threads: u32,
    /// Tasks it holds now.
    pub leases: usize,
    /// In this process, or trusted by config: its outcomes are never checked.
    pub trusted: bool,
    /// Caught disagreeing with a check: every later call is refused.
    pub quarantined: bool,
    /// Seconds since its last call.
    pub idle_seconds: f64,
}

impl TaskQueue {
    /// Every registered worker, lowest id first.
    pub fn workers(&self, now: Instant) -> Vec<WorkerView> {
        let s = self.lock();
        let mut ids: Vec<_> = s.workers.keys().copied().collect();
        ids.sort_by_key(|id| id.serial);
        ids.into_iter()
            .map(|id| {
                let w = &s.workers[&id];
                WorkerView {
                    label: format!("{} ({id})", w.name),
                    principal: w.principal.to_string(),
                    threads: w.capacity,
                    leases: w.leased.len(),
                    trusted: w.trusted,
                    quarantined: s.quarantined.contains(&id)
                        || s.quarantined_principals.contains(&w.principal),
                    idle_seconds: now.saturating_duration_since(w.last_seen).as_secs_f64(),
                }
            })
            .collect()
    }
}
