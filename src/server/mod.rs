//! The server: the I/O shell around the simulation core (tokio, axum, tower). Matches
//! are tasks that tick their worlds, on a runtime of their own so that a match's clock
//! never waits behind the sockets; sockets and REST requests talk to them through
//! channels and a shared table. Nothing here changes what a world computes.
//!
//! * [`config`]: settings, defaults and the TOML file.
//! * [`state`]: the shared table of matches and what a match publishes.
//! * [`match_task`]: the tick loop of one match (realtime, fast, lockstep).
//! * [`ws`]: spectator and bot WebSockets.
//! * [`replays`]: recorded matches: listed, downloaded, played with controls.
//! * [`replay_dir`]: which files in the replay directory are replays, opened safely.
//! * [`range`]: HTTP byte ranges, for resuming a download.
//! * [`recording`]: writing a match's replay on a thread of its own, bounded.
//! * [`retention`]: deleting the oldest replays past the configured size and age.
//! * [`api`]: the REST API, health, readiness and metrics.
//! * [`auth`]: tokens, compared in constant time.
//! * [`admission`]: who may open a WebSocket: origin policy, connections per address.
//! * [`metrics`]: Prometheus counters.
//! * [`demo`]: the built-in demo matches.
//! * [`agones`]: running as an Agones game server (Ready, Health, Shutdown).
//! * [`web`]: the spectator page from `web/`, embedded in the binary.

pub mod admission;
pub mod agones;
pub mod api;
pub mod auth;
pub mod config;
pub mod demo;
pub mod match_task;
pub mod metrics;
pub mod range;
pub mod recording;
pub mod replay_dir;
pub mod replays;
pub mod retention;
pub mod state;
pub mod web;
pub mod ws;

pub use config::ServerConfig;

use crate::basketball::Capabilities;
use axum::routing::get;
use axum::Router;
use state::AppState;
use std::collections::BTreeMap;
use std::future::Future;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, RwLock};
use std::time::{Duration, Instant};
use tokio::net::TcpListener;
use tokio::sync::watch;
use tower_http::limit::RequestBodyLimitLayer;
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;

/// How long a stopping server waits for its replays to be written, synced and closed.
const REPLAYS_FINISH_WITHIN: Duration = Duration::from_secs(10);

/// Runs the server on `listener` until `shutdown` completes; then every match ends,
/// every socket is closed with 1001, and it returns.
pub async fn serve(
    listener: TcpListener,
    config: ServerConfig,
    admin_token: String,
    caps: Arc<Capabilities>,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let (stop_tx, stop_rx) = watch::channel(false);
    // Matches tick on a runtime of their own, apart from the one serving sockets: there
    // a tick waited in the same queue as the fan-out of the previous frame to every
    // spectator, and at 1,000 spectators sometimes started a whole period late.
    let ticking = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .thread_name("fieldhouse-ticks")
        .enable_all()
        .build()?;
    let app = Arc::new(AppState {
        ticking: ticking.handle().clone(),
        config: config.clone(),
        admin_token,
        caps,
        metrics: Arc::default(),
        matches: RwLock::new(BTreeMap::new()),
        shutdown: stop_rx,
        next_conn: AtomicU64::new(0),
        replay_dir: config.replay_dir.clone(),
        replays: replay_dir::Replays::default(),
        replay_written: tokio::sync::Notify::new(),
        connections: admission::Connections::default(),
    });
    if config.demo {
        demo::start_all(&app);
    }
    tokio::spawn(retention::run(app.clone()));
    let agones = config.agones_sdk_port.map(agones::Sdk::on_port);
    if let Some(sdk) = &agones {
        tokio::spawn(sdk.clone().ready_then_healthy(app.shutdown.clone()));
    }
    let router = router(app.clone());
    // Under Agones the server is done once its matches are; elsewhere it serves until
    // told to stop.
    let done = agones.is_some().then(|| agones::matches_done(app.clone()));
    let graceful = async move {
        match done {
            Some(done) => tokio::select! {
                _ = shutdown => {}
                _ = done => tracing::info!("every match has ended"),
            },
            None => shutdown.await,
        }
        tracing::info!("shutting down: ending matches and closing sockets");
        let _ = stop_tx.send(true);
        // Give sockets a moment to send their close frames.
        tokio::time::sleep(Duration::from_millis(200)).await;
    };
    // Sockets are counted per client address, so handlers need the peer's.
    let service = router.into_make_service_with_connect_info::<std::net::SocketAddr>();
    let served = axum::serve(listener, service)
        .with_graceful_shutdown(graceful)
        .await;
    // The matches have ended by now: the graceful shutdown gave them 200 ms after the
    // stop, and a match ends at the next tick. Their replays are finished on writer
    // threads, which the process must not end under: wait for them (a while at most).
    let writing = Instant::now();
    while !app.replays.writing.lock().expect("not poisoned").is_empty()
        && writing.elapsed() < REPLAYS_FINISH_WITHIN
    {
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    ticking.shutdown_background();
    if let Some(sdk) = &agones {
        sdk.shutdown().await;
    }
    served
}

pub fn router(app: Arc<AppState>) -> Router {
    let config = &app.config;
    let api = Router::new()
        .route("/api/matches", get(api::list).post(api::create))
        .route("/api/matches/{id}", get(api::show).delete(api::delete))
        .route("/api/matches/{id}/costmap/{agent}", get(api::costmap))
        .route("/api/costmaps/{behaviour}", get(api::behaviour_costmap))
        .route("/api/replays", get(replays::list))
        .route("/api/replays/{id}", get(replays::download))
        .route("/healthz", get(api::healthz))
        .route("/readyz", get(api::readyz))
        .route("/metrics", get(api::metrics))
        .layer(TimeoutLayer::with_status_code(
            axum::http::StatusCode::REQUEST_TIMEOUT,
            Duration::from_millis(config.request_timeout_ms),
        ))
        .layer(RequestBodyLimitLayer::new(config.max_body_bytes));
    Router::new()
        .merge(api)
        .route("/ws/matches/{id}", get(ws::spectate))
        .route("/ws/matches/{id}/play", get(ws::play))
        .route("/ws/replays/{id}", get(replays::watch))
        .route("/", get(web::index))
        .route("/web/{file}", get(web::file))
        .fallback(api::fallback)
        .layer(axum::middleware::map_response(api::json_errors))
        // Requests are logged by path only: a bot's token may ride in the query string
        // (`?token=T`), and no token may reach the logs.
        .layer(TraceLayer::new_for_http().make_span_with(
            |request: &axum::http::Request<axum::body::Body>| {
                tracing::debug_span!("request", method = %request.method(), path = %request.uri().path())
            },
        ))
        .with_state(app)
}
