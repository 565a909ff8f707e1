//! How much of the queue one worker may take, and for how long.
//!
//! - **Share.** While workers of other principals wait for work, a principal holds at most its
//!   max-min fair share of the batch's open tasks (queued or leased), whatever the capacities its
//!   workers declare: a worker asking for 1,024 tasks beside one asking for 1 leaves that one its
//!   task. With nobody else waiting, a worker takes up to its capacity.
//! - **Return.** A task whose lease lapsed or was handed back goes to another principal first; a
//!   check never goes back to the principal that let it lapse (the coordinator makes it).
//! - **Backup.** A worker with room and nothing queued for it takes over a task another
//!   principal's outside worker has held for more than twice the median evaluation time (the
//!   backup tasks of MapReduce): the first outcome of either counts, so nobody's idle worker waits
//!   on a task someone sits on.
//! - **Lifetime.** A lease lives at most eight times the median time between a grant and its
//!   report over the last [`SAMPLES`] reports (measured here, not taken from workers), within
//!   `[lease, max_lease]`: a worker that names its leases in every heartbeat and never reports
//!   keeps them for a few evaluations' time, not for `max_lease`.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::time::{Duration, Instant};

use super::task::{TaskState, Voice};
use super::{QueueRules, State, WorkerState};
use crate::ids::WorkerId;
use crate::principal::Principal;

/// Reports the lease lifetime is measured over.
const SAMPLES: usize = 64;
/// Reports measured before the lifetime follows them (until then: `max_lease`).
const MIN_SAMPLES: usize = 8;
/// Lifetime in medians of the measured evaluation time.
const MEDIANS_PER_LIFETIME: u32 = 8;
/// A worker whose lease call left slots unfilled this recently is waiting for work (a lease call
/// waits at most 5 s before it asks again).
pub(super) const WAITING_WINDOW: Duration = Duration::from_secs(6);

impl WorkerState {
    pub(super) fn waiting(&self, now: Instant) -> bool {
        self.wants > 0 && now.saturating_duration_since(self.last_asked) <= WAITING_WINDOW
    }
}

/// Max-min fair division of `total` among `demands`: each gets its demand or an equal part of
/// what is left, whichever is smaller (parts rounded up, so nothing is left over for want of a
/// unit).
pub(super) fn max_min(total: u64, demands: &[u64]) -> Vec<u64> {
    let mut order: Vec<usize> = (0..demands.len()).collect();
    // Stable: among equal demands the earlier gets the part rounded up.
    order.sort_by_key(|&i| demands[i]);
    let mut alloc = vec![0; demands.len()];
    let mut left = total;
    for (k, &i) in order.iter().enumerate() {
        let part = left.div_ceil((demands.len() - k) as u64);
        alloc[i] = demands[i].min(part);
        left = left.saturating_sub(alloc[i]);
    }
    alloc
}

impl State {
    /// How many of `room` slots `worker` may fill now. Another worker's demand is what it waits
    /// for and may take (a check it may not make, a task it failed, are no demand of its).
    pub(super) fn allowance(&self, worker: WorkerId, room: u32, now: Instant) -> u32 {
        let me = &self.workers[&worker];
        // The common case, one principal (or local workers alone) at work, costs one pass.
        if !self
            .workers
            .values()
            .any(|w| w.principal != me.principal && w.waiting(now))
        {
            return room;
        }
        // Per principal: tasks held, and tasks its workers wait for. The caller's principal goes
        // first, so a tie is broken in favour of the worker that is asking.
        let mut principals: BTreeMap<(bool, &Principal), (u64, u64)> = BTreeMap::new();
        // Waiting workers by voice (what they may take depends on nothing else), so the queue
        // is scanned once per voice, not once per worker: (slots wanted, one of them).
        let mut waiting: HashMap<Voice, (u64, WorkerId)> = HashMap::new();
        for (&id, w) in &self.workers {
            let entry = principals
                .entry((w.principal != me.principal, &w.principal))
                .or_default();
            entry.0 += w.leased.len() as u64;
            if id == worker {
                entry.1 += u64::from(room);
            } else if w.waiting(now) {
                waiting.entry(w.voice(id)).or_insert((0, id)).0 += u64::from(w.wants);
            }
        }
        let mut others_wait = false;
        for (wants, id) in waiting.into_values() {
            let w = &self.workers[&id];
            let wanted = self
                .queued
                .iter()
                .filter(|t| self.tasks[t].may_take(id, w))
                .take(wants as usize)
                .count() as u64;
            principals
                .get_mut(&(w.principal != me.principal, &w.principal))
                .expect("counted above")
                .1 += wanted;
            others_wait |= wanted > 0 && w.principal != me.principal;
        }
        if !others_wait {
            return room;
        }
        let open = self.queued.len() as u64 + principals.values().map(|p| p.0).sum::<u64>();
        let demands: Vec<u64> = principals
            .values()
            .map(|(held, wants)| held + wants)
            .collect();
        let alloc = max_min(open, &demands);
        let held = principals[&(false, &me.principal)].0;
        alloc[0].saturating_sub(held).min(u64::from(room)) as u32
    }

    /// Whether `t` should wait for another principal: `principal` handed it back or let its lease
    /// lapse, and it is a check (which then goes to the coordinator) or a worker of another
    /// principal that may take it is waiting.
    pub(super) fn goes_to_another_first(
        &self,
        t: &TaskState,
        principal: &Principal,
        now: Instant,
    ) -> bool {
        t.returned_by.contains(principal)
            && (t.task.id.is_check()
                || self.workers.iter().any(|(&id, w)| {
                    w.principal != *principal && w.waiting(now) && t.may_take(id, w)
                }))
    }

    /// How long a lease granted now may live, heartbeats or not.
    pub(super) fn lease_lifetime(&self, rules: &QueueRules) -> Duration {
        lifetime(self.lease_times.median, rules)
    }

    /// How long another principal's outside worker may hold a task before a waiting worker takes
    /// it over: twice the median measured evaluation, once measured (until then, `lease`).
    pub(super) fn backup_after(&self, rules: &QueueRules) -> Duration {
        match self.lease_times.median {
            Some(m) => (m * 2).max(rules.heartbeat_interval),
            None => rules.lease,
        }
    }
}

/// Grant-to-report times of the last [`SAMPLES`] accepted reports and their median, kept as they
/// come (once per report) so that granting a lease reads it without sorting.
#[derive(Debug, Default)]
pub(super) struct LeaseTimes {
    samples: VecDeque<Duration>,
    /// Set once [`MIN_SAMPLES`] are in.
    median: Option<Duration>,
}

impl LeaseTimes {
    pub(super) fn measure(&mut self, granted: Instant, now: Instant) {
        if self.samples.len() == SAMPLES {
            self.samples.pop_front();
        }
        self.samples
            .push_back(now.saturating_duration_since(granted));
        if self.samples.len() >= MIN_SAMPLES {
            let mut sorted: Vec<Duration> = self.samples.iter().copied().collect();
            sorted.sort_unstable();
            self.median = Some(sorted[sorted.len() / 2]);
        }
    }
}

fn lifetime(median: Option<Duration>, rules: &QueueRules) -> Duration {
    match median {
        Some(m) => {
            (m * MEDIANS_PER_LIFETIME).clamp(rules.lease.min(rules.max_lease), rules.max_lease)
        }
        None => rules.max_lease,
    }
}

#[cfg(test)]
mod tests;
