//! The dashboard's HTTP server, on the caller's tokio runtime: the page's three embedded files,
//! `GET /api/status` and `GET /api/design.png?task=ID`. Store reads run on blocking threads, one
//! at a time (the view keeps its read connection and the history read so far).

use std::net::SocketAddr;
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use amorph::report::render_isometric;
use amorph::task::Scene;
use axum::Router;
use axum::extract::{Query, Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use tokio::sync::oneshot;
use tokio::task::JoinHandle;
use tracing::warn;

use super::store_view::{StoreView, StoreViewError};
use crate::cluster::credentials::constant_time_eq;
use crate::cluster::queue::TaskQueue;

const INDEX_HTML: &str = include_str!("assets/index.html");
const APP_JS: &str = include_str!("assets/app.js");
const STYLE_CSS: &str = include_str!("assets/style.css");

/// Pixels per voxel edge of the best design's picture (the report's island pictures use the same).
const VOXEL_PIXELS: f64 = 8.0;

#[derive(Debug, thiserror::Error)]
pub enum DashboardError {
    #[error("dashboard: cannot listen on {listen}: {source}")]
    Listen {
        listen: String,
        source: std::io::Error,
    },
    #[error(
        "dashboard: {addr} is reachable beyond this machine, but the run has no token to ask for: set AMORPH_TOKEN or cluster.token_file, or listen on 127.0.0.1"
    )]
    NoToken { addr: SocketAddr },
    #[error(transparent)]
    Store(#[from] StoreViewError),
}

/// A dashboard being served; dropping it (or [`Dashboard::shutdown`]) stops it.
#[derive(Debug)]
pub struct Dashboard {
    pub addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    task: Option<JoinHandle<()>>,
}

impl Dashboard {
    /// The page's address (with the token to pass, when one is asked for).
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    pub async fn shutdown(mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(task) = self.task.take() {
            // A browser's open connection may hold a graceful shutdown up: give it a second.
            let abort = task.abort_handle();
            if tokio::time::timeout(std::time::Duration::from_secs(1), task)
                .await
                .is_err()
            {
                abort.abort();
            }
        }
    }
}

impl Drop for Dashboard {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
    }
}

struct Shared {
    view: Mutex<StoreView>,
    scene: Scene,
    /// The coordinator's queue while a run goes; `None` when serving a store.
    queue: Option<Arc<TaskQueue>>,
    token: Option<String>,
    /// The last picture drawn: (task id, PNG).
    picture: Mutex<Option<(u64, Arc<[u8]>)>>,
}

/// A dashboard's listening socket, bound before the run store is touched (so an address in use
/// leaves no store behind), with the token its requests must carry.
#[derive(Debug)]
pub struct Bound {
    listener: tokio::net::TcpListener,
    addr: SocketAddr,
    token: Option<String>,
}

/// Listens on `listen`. Beyond loopback, requests must carry `token`; without one the dashboard
/// refuses to listen there.
pub async fn bind(listen: &str, token: Option<String>) -> Result<Bound, DashboardError> {
    let listen_error = |source| DashboardError::Listen {
        listen: listen.to_owned(),
        source,
    };
    let listener = tokio::net::TcpListener::bind(listen)
        .await
        .map_err(listen_error)?;
    let addr = listener.local_addr().map_err(listen_error)?;
    let token = if addr.ip().is_loopback() {
        None
    } else {
        Some(token.ok_or(DashboardError::NoToken { addr })?)
    };
    Ok(Bound {
        listener,
        addr,
        token,
    })
}

impl Bound {
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Serves the dashboard of the run whose store is at `store`. `queue` is the running
    /// coordinator's (live), or `None` to serve the store alone.
    pub async fn serve(
        self,
        store: &Path,
        queue: Option<Arc<TaskQueue>>,
    ) -> Result<Dashboard, DashboardError> {
        let Self {
            listener,
            addr,
            token,
        } = self;
        let path = store.to_owned();
        let view = tokio::task::spawn_blocking(move || StoreView::open(&path))
            .await
            .map_err(|e| StoreViewError {
                path: store.to_owned(),
                message: e.to_string(),
            })??;
        let shared = Arc::new(Shared {
            scene: view.config().scene.clone(),
            view: Mutex::new(view),
            queue,
            token,
            picture: Mutex::new(None),
        });
        let app = Router::new()
            .route(
                "/",
                get(|| async { asset("text/html; charset=utf-8", INDEX_HTML) }),
            )
            .route(
                "/app.js",
                get(|| async { asset("text/javascript; charset=utf-8", APP_JS) }),
            )
            .route(
                "/style.css",
                get(|| async { asset("text/css; charset=utf-8", STYLE_CSS) }),
            )
            .route("/api/status", get(status))
            .route("/api/design.png", get(design))
            .layer(middleware::from_fn_with_state(shared.clone(), authorize))
            .with_state(shared);
        let (stop, stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let served = axum::serve(listener, app).with_graceful_shutdown(async {
                let _ = stopped.await;
            });
            if let Err(e) = served.await {
                warn!(error = %e, "dashboard stopped");
            }
        });
        Ok(Dashboard {
            addr,
            stop: Some(stop),
            task: Some(task),
        })
    }
}

fn asset(content_type: &'static str, body: &'static str) -> Response {
    ([(header::CONTENT_TYPE, content_type)], body).into_response()
}

/// Every request carries the token when one is asked for: in `authorization: Bearer`, or as the
/// address's `token` parameter (how a browser opens the page and asks for a picture).
async fn authorize(
    State(shared): State<Arc<Shared>>,
    Query(query): Query<Vec<(String, String)>>,
    headers: HeaderMap,
    request: Request,
    next: Next,
) -> Response {
    let Some(token) = &shared.token else {
        return next.run(request).await;
    };
    let from_header = (headers.get(header::AUTHORIZATION))
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "));
    let from_query = query
        .iter()
        .find(|(k, _)| k == "token")
        .map(|(_, v)| v.as_str());
    let offered = from_header.or(from_query).unwrap_or("");
    if constant_time_eq(offered.trim().as_bytes(), token.as_bytes()) {
        next.run(request).await
    } else {
        let mut refused = (
            StatusCode::UNAUTHORIZED,
            "this dashboard asks for the run's token: open it as http://HOST:PORT/?token=TOKEN\n",
        )
            .into_response();
        refused
            .headers_mut()
            .insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
        refused
    }
}

async fn status(State(shared): State<Arc<Shared>>) -> Response {
    let result = tokio::task::spawn_blocking(move || {
        let live = shared.queue.is_some();
        let now = live.then(crate::store::unix_now);
        let status = shared
            .view
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .status(now)?;
        Ok::<_, StoreViewError>(match &shared.queue {
            Some(queue) => status.with_live(queue.workers(Instant::now()), queue.stats()),
            None => status,
        })
    })
    .await;
    match result {
        Ok(Ok(status)) => match serde_json::to_vec(&status) {
            Ok(body) => (
                [
                    (header::CONTENT_TYPE, "application/json"),
                    (header::CACHE_CONTROL, "no-store"),
                ],
                body,
            )
                .into_response(),
            Err(e) => server_error(e.to_string()),
        },
        Ok(Err(e)) => server_error(e.to_string()),
        Err(e) => server_error(e.to_string()),
    }
}

/// The picture of evaluation `task`'s design at its resolution, as the report draws it.
async fn design(
    State(shared): State<Arc<Shared>>,
    Query(query): Query<Vec<(String, String)>>,
) -> Response {
    let Some(task) = (query.iter())
        .find(|(k, _)| k == "task")
        .and_then(|(_, v)| v.parse::<u64>().ok())
    else {
        return (
            StatusCode::BAD_REQUEST,
            "task=ID (an evaluation's task id) is required\n",
        )
            .into_response();
    };
    let result = tokio::task::spawn_blocking(move || picture(&shared, task)).await;
    match result {
        Ok(Ok(Some(png))) => (
            [
                (header::CONTENT_TYPE, "image/png"),
                // An evaluation's design never changes.
                (header::CACHE_CONTROL, "max-age=86400, immutable"),
            ],
            png.to_vec(),
        )
            .into_response(),
        Ok(Ok(None)) => (StatusCode::NOT_FOUND, format!("no evaluation {task}\n")).into_response(),
        Ok(Err(e)) => server_error(e),
        Err(e) => server_error(e.to_string()),
    }
}

fn picture(shared: &Shared, task: u64) -> Result<Option<Arc<[u8]>>, String> {
    if let Some((id, png)) = &*shared.picture.lock().unwrap_or_else(|e| e.into_inner())
        && *id == task
    {
        return Ok(Some(png.clone()));
    }
    let design = (shared.view.lock().unwrap_or_else(|e| e.into_inner()))
        .design(task)
        .map_err(|e| e.to_string())?;
    let Some((genome, dims)) = design else {
        return Ok(None);
    };
    let grid = shared.scene.design(&genome, dims);
    let png: Arc<[u8]> = render_isometric(&grid, shared.scene.palette(), VOXEL_PIXELS)
        .to_png()
        .map_err(|e| e.to_string())?
        .into();
    *shared.picture.lock().unwrap_or_else(|e| e.into_inner()) = Some((task, png.clone()));
    Ok(Some(png))
}

fn server_error(message: String) -> Response {
    warn!(%message, "dashboard request failed");
    (StatusCode::INTERNAL_SERVER_ERROR, message + "\n").into_response()
}
