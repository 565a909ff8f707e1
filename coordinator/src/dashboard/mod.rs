//! The live dashboard: a page in the browser that follows a run, served over HTTP by the
//! coordinator itself (`coordinator --dashboard ADDR`, `[dashboard] listen`) or from a run's store
//! (`coordinator dashboard results/<run>/run.sqlite`).
//!
//! Everything it shows comes from the run store (`store_view`), read-only and incrementally, so
//! the page is the same live and afterwards; a running coordinator adds its queue's view of the
//! workers. The page polls `GET /api/status` (the JSON in `status`, documented in
//! docs/reference/dashboard.md) every two seconds; its HTML, script and style are compiled into
//! the binary, so an offline cluster serves it whole. It only reads. Listening beyond loopback it
//! asks for the run's token (`authorization: Bearer TOKEN`, or `?token=TOKEN` in the address,
//! which the page passes on).

mod server;
mod status;
mod store_view;

pub use server::{Bound, Dashboard, DashboardError, bind};
pub use status::Status;
pub use store_view::{StoreView, StoreViewError};

use serde::{Deserialize, Serialize};

/// The `[dashboard]` section.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DashboardSection {
    /// Address the dashboard is served on while the run goes (e.g. 127.0.0.1:8080; port 0 picks a
    /// free one). Unset: no dashboard.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub listen: Option<String>,
}

impl DashboardSection {
    pub fn is_default(&self) -> bool {
        self == &Self::default()
    }
}
