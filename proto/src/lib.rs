//! The coordinator–worker gRPC protocol (`amorph.v1`), generated at build time, plus the edge
//! conversions to the domain types of the shared library.

pub mod convert;
pub mod grid;
pub mod ids;
pub mod signal;

#[allow(missing_debug_implementations, clippy::all)]
pub mod v1 {
    tonic::include_proto!("amorph.v1");
}

/// The version both sides must speak; bump it with any incompatible change to the `.proto`.
/// Version 2: heartbeats carry the version too. Version 3: Register returns a session secret that
/// every later call carries. Version 4: a divergence is reported as its kind, value and limit.
pub const PROTOCOL_VERSION: u32 = 4;

/// Largest message either side decodes or encodes. A genome at the paper's scale is a few kB and a
/// locomotion outcome's metrics a few tens of kB; 16 MiB leaves room for genomes of many thousands
/// of points while bounding what a hostile peer can make us allocate.
pub const MAX_MESSAGE_BYTES: usize = 16 << 20;

/// gRPC metadata key carrying the shared-secret token (`authorization: Bearer <token>`).
pub const AUTHORIZATION: &str = "authorization";
