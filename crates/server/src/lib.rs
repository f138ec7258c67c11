//! The server: the I/O shell around the simulation core (tokio, axum, tower). Matches
//! are tasks that tick their worlds, on a runtime of their own so that a match's clock
//! never waits behind the sockets; sockets and REST requests talk to them through
//! channels and a shared table. Nothing here changes what a world computes.
//!
//! * [`config`]: settings, defaults and the TOML file.
//! * [`state`]: the shared table of matches and what a match publishes.
//! * [`match_task`]: the tick loop of one match (realtime, fast, lockstep).
//! * [`slot`]: a match's place among the `max_matches`, taken atomically.
//! * [`sweep`]: ended matches leave the table after a while.
//! * [`spectator`]: the spectator WebSocket: a match's frames, newest first.
//! * [`fanout`]: a match's frames written straight to its spectators' sockets, by a few
//!   tasks, one write per socket per frame; its [`fanout::Wire`] is a spectator's socket,
//!   written whole frames at a time by the fan-out and everyone else.
//! * [`bot`]: the bot WebSocket: an agent's perceptions out, commands in.
//! * [`socket`]: what every WebSocket shares: close codes, reading, writing under a
//!   timeout, closing.
//! * [`replays`]: recorded matches: listed, downloaded, played with controls.
//! * [`replay_dir`]: which files in the replay directory are replays, opened safely.
//! * [`range`]: HTTP byte ranges, for resuming a download.
//! * [`recording`]: writing a match's replay on a thread of its own, bounded.
//! * [`retention`]: deleting the oldest replays past the configured size and age.
//! * [`api`]: the REST API, health, readiness and metrics.
//! * [`error`]: the JSON error every HTTP endpoint answers with, and its status.
//! * [`auth`]: tokens, compared in constant time.
//! * [`listener`]: the accept loop: every connection counted and capped (per address
//!   and in all), header and idle timeouts, descriptors kept for health checks.
//! * [`upgrade`]: the WebSocket handshake and the frame meter under every socket.
//! * [`admission`]: who may open a WebSocket: origin and host policy, room for
//!   spectators.
//! * [`hosts`]: what a Host or Origin header and the allowed hosts and origins may name.
//! * [`wall`]: the time of day, read in one place (the core has no clock).
//! * [`metrics`]: Prometheus counters.
//! * [`motion`]: the motion poses a spectator poses skeletons from, served once.
//! * [`demo`]: the built-in demo matches.
//! * [`agones`]: running as an Agones game server (Ready, Health, Shutdown).
//! * [`web`]: the spectator page from `web/`, embedded in the binary.

// Every public item of the server is documented: the binary, the load generator and the
// tests build on it, and its documentation is where limits, timeouts and who may do
// what are stated.
#![warn(missing_docs)]

pub mod admission;
pub mod agones;
pub mod api;
pub mod auth;
pub mod bot;
pub mod config;
pub mod demo;
pub mod error;
pub mod fanout;
pub mod hosts;
pub mod listener;
pub mod match_task;
pub mod metrics;
pub mod motion;
pub mod range;
pub mod recording;
pub mod replay_dir;
pub mod replays;
pub mod retention;
pub mod slot;
pub mod socket;
pub mod spectator;
pub mod state;
pub mod sweep;
pub mod upgrade;
pub mod wall;
pub mod web;

pub use config::ServerConfig;

use axum::error_handling::HandleErrorLayer;
use axum::http::StatusCode;
use axum::routing::get;
use axum::Router;
use fieldhouse_core::basketball::Capabilities;
use state::AppState;
use std::collections::BTreeMap;
use std::future::Future;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, RwLock};
use std::time::{Duration, Instant};
use tokio::net::TcpListener;
use tokio::sync::watch;
use tower::ServiceBuilder;
use tower_http::limit::RequestBodyLimitLayer;
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;

/// How long a stopping server waits for its replays to be written, synced and closed.
const REPLAYS_FINISH_WITHIN: Duration = Duration::from_secs(10);

/// Runs the server on `listener` until `shutdown` completes; then every match ends,
/// every socket is closed with 1001, and it returns. Raises the process's descriptor
/// limit to its hard limit (see [`listener::connection_budget`]).
pub async fn serve(
    listener: TcpListener,
    config: ServerConfig,
    admin_token: auth::AdminToken,
    caps: Arc<Capabilities>,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let budget = listener::connection_budget();
    let max_connections = match config.max_connections {
        Some(n) if n > budget => {
            tracing::warn!(
                max_connections = n,
                budget,
                "max_connections is more than the descriptor limit allows; using {budget} (raise it with ulimit -n)"
            );
            budget
        }
        Some(n) => n,
        None => budget,
    };
    let connections = Arc::new(listener::Connections::new(
        config.max_connections_per_ip,
        max_connections,
    ));
    tracing::info!(max_connections, "connection limit");
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
        connections: connections.clone(),
    });
    if config.demo {
        demo::start_all(&app);
    }
    tokio::spawn(sweep::run(app.clone()));
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
    let settings = listener::Listening {
        connections,
        header_timeout: Duration::from_millis(config.header_timeout_ms),
        write_timeout: Duration::from_millis(config.send_timeout_ms),
        metrics: app.metrics.clone(),
    };
    listener::serve(listener, router, settings, graceful).await;
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
    Ok(())
}

/// The server's routes (REST API, WebSockets, health, metrics, the page) with the layers
/// every request goes through: limits, timeouts, load shedding and security headers.
pub fn router(app: Arc<AppState>) -> Router {
    let config = &app.config;
    let metrics = app.metrics.clone();
    // More requests in flight than the limit are answered 503 at once rather than
    // queued: a queue would hold their connections and memory while they wait. The
    // limit is global: a router applies a layer to every route (and every method of
    // it) apart, and a plain concurrency limit would give each its own.
    let shed = ServiceBuilder::new()
        .layer(HandleErrorLayer::new(move |_: tower::BoxError| {
            metrics.overloaded.fetch_add(1, Relaxed);
            std::future::ready(error::ApiError::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "overloaded",
                "too many requests in flight (max_concurrent_requests); try again",
            ))
        }))
        .load_shed()
        .layer(tower::limit::GlobalConcurrencyLimitLayer::new(
            config.max_concurrent_requests,
        ));
    let api = Router::new()
        .route("/api/matches", get(api::list).post(api::create))
        .route("/api/matches/{id}", get(api::show).delete(api::delete))
        .route("/api/matches/{id}/costmap/{agent}", get(api::costmap))
        .route("/api/costmaps/{behaviour}", get(api::behaviour_costmap))
        .route("/api/motion/{behaviour}", {
            let docs = Arc::new(motion::PoseDocuments::new(app.caps.clone()));
            get(move |behaviour, request| motion::poses(behaviour, docs.clone(), request))
        })
        .route("/api/replays", get(replays::list))
        .route("/api/replays/{id}", get(replays::download))
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            Duration::from_millis(config.request_timeout_ms),
        ))
        .layer(RequestBodyLimitLayer::new(config.max_body_bytes))
        .layer(shed);
    // Health, readiness and metrics stay outside the limit: an orchestrator must be able
    // to ask while the API is saturated.
    let probes = Router::new()
        .route("/healthz", get(api::healthz))
        .route("/readyz", get(api::readyz))
        .route("/metrics", get(api::metrics));
    Router::new()
        .merge(api)
        .merge(probes)
        .route("/ws/matches/{id}", get(spectator::spectate))
        .route("/ws/matches/{id}/play", get(bot::play))
        .route("/ws/replays/{id}", get(replays::watch))
        .route("/", get(web::index))
        .route("/web/{file}", get(web::file))
        .fallback(api::fallback)
        .layer(axum::middleware::map_response(api::json_errors))
        .layer(axum::middleware::map_response(web::security_headers))
        // Requests are logged by path only: a bot's token may ride in the query string
        // (`?token=T`), and no token may reach the logs.
        .layer(TraceLayer::new_for_http().make_span_with(
            |request: &axum::http::Request<axum::body::Body>| {
                tracing::debug_span!("request", method = %request.method(), path = %request.uri().path())
            },
        ))
        .with_state(app)
}
