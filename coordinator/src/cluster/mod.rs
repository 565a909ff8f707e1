//! The cluster: the task queue with leases, the gRPC service workers call, the server that hosts
//! it, and the evaluator the search uses to hand batches to the cluster.

pub mod connections;
pub mod credentials;
pub mod evaluator;
pub mod local;
pub mod peer_text;
pub mod queue;
pub mod server;
pub mod service;
pub mod settings;
pub mod status;

pub use evaluator::ClusterEvaluator;
pub use queue::{QueueRules, QueueStats, TaskQueue};
pub use server::{ServerHandle, ServerOptions, start};
pub use settings::{ClusterSection, ClusterSettings, Verify};
