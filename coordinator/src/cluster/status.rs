//! Every refusal at the cluster edge as one gRPC status: the queue's errors, malformed requests and
//! wire-format errors map here and nowhere else, so a code means the same in every call and the
//! docs' table (docs/reference/protocol.md) has one source. Peer-supplied text in a message passes
//! through [`peer_text::clean`] first.

use amorph_proto::PROTOCOL_VERSION;
use tonic::Status;

use super::peer_text::{self, MAX_ID_CHARS};
use super::queue::QueueError;
use crate::ids::WorkerId;

/// Most results per report, ids per heartbeat or release.
pub const MAX_IDS_PER_CALL: usize = 4096;
/// Largest capacity a worker may claim.
pub const MAX_CAPACITY: u32 = 1024;

impl From<QueueError> for Status {
    fn from(e: QueueError) -> Self {
        match e {
            QueueError::UnknownWorker(_) | QueueError::UnknownTask(_) => {
                Status::not_found(e.to_string())
            }
            QueueError::NotLeasedTo { .. } => Status::failed_precondition(e.to_string()),
            QueueError::Quarantined(_) => Status::permission_denied(e.to_string()),
            QueueError::TooManyWorkers | QueueError::TooManyForCredential { .. } => {
                Status::resource_exhausted(e.to_string())
            }
            QueueError::BadSession(_) => Status::unauthenticated(e.to_string()),
        }
    }
}

/// The worker id of a request: a well-formed id of some coordinator, or `NOT_FOUND` (as an id
/// this coordinator never issued is), with the text escaped and capped.
pub fn worker_id(text: &str) -> Result<WorkerId, Status> {
    text.parse().map_err(|()| {
        Status::not_found(format!(
            "worker '{}' is not registered (register again)",
            peer_text::clean(text, MAX_ID_CHARS)
        ))
    })
}

/// The protocol version of a register or heartbeat.
pub fn protocol_version(version: u32) -> Result<(), Status> {
    if version == PROTOCOL_VERSION {
        return Ok(());
    }
    Err(Status::failed_precondition(format!(
        "protocol version {version} is not supported: this coordinator speaks version {PROTOCOL_VERSION}"
    )))
}

pub fn capacity(capacity: u32) -> Result<(), Status> {
    if (1..=MAX_CAPACITY).contains(&capacity) {
        return Ok(());
    }
    Err(Status::invalid_argument(format!(
        "capacity = {capacity} must be between 1 and {MAX_CAPACITY}"
    )))
}

/// A list field of a request holding at most [`MAX_IDS_PER_CALL`] entries.
pub fn list_length(field: &str, n: usize) -> Result<(), Status> {
    if n <= MAX_IDS_PER_CALL {
        return Ok(());
    }
    Err(Status::invalid_argument(format!(
        "{field}: {n} entries, at most {MAX_IDS_PER_CALL} per call"
    )))
}

pub fn unknown_scene(scene_id: &str) -> Status {
    Status::not_found(format!(
        "scene '{}' is not this run's scene",
        peer_text::clean(scene_id, MAX_ID_CHARS)
    ))
}

#[cfg(test)]
mod tests;
