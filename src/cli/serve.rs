//! `fieldhouse serve`: the match server.

use super::basketball::CapabilityArgs;
use anyhow::Context;
use clap::Args;
use fieldhouse::server::config::{listen_addr, DEFAULT_PORT};
use fieldhouse::server::{self, auth, ServerConfig};
use std::io::ErrorKind;
use std::net::{SocketAddr, TcpListener};
use std::path::PathBuf;

#[derive(Args, Debug)]
#[command(
    after_help = "Open http://127.0.0.1:7878/ to watch. Creating and deleting matches needs the admin token: \
    set FIELDHOUSE_ADMIN_TOKEN, or use the one printed at start.\n\
    Example: fieldhouse serve"
)]
pub(super) struct ServeArgs {
    /// Address to listen on: HOST:PORT, where HOST is an IP address or a host name
    /// (127.0.0.1:7878, localhost:8080, [::1]:7878; 0.0.0.0:7878 for every interface),
    /// or a HOST alone for port 7878. Default 127.0.0.1:7878: loopback only.
    #[arg(long, env = "FIELDHOUSE_ADDR", value_name = "HOST:PORT", value_parser = listen_addr)]
    addr: Option<SocketAddr>,
    /// Do not start the built-in demo matches.
    #[arg(long)]
    no_demo: bool,
    /// Record every match as a replay file in this directory (created if missing);
    /// `GET /api/replays` lists them and `/ws/replays/{id}` plays them.
    #[arg(long, value_name = "DIR", env = "FIELDHOUSE_REPLAY_DIR")]
    replay_dir: Option<PathBuf>,
    /// Keep the replays in --replay-dir under this many bytes in all, deleting the
    /// oldest first (never one being written). Default 2 GiB (2147483648).
    #[arg(long, value_name = "BYTES")]
    replay_retention_bytes: Option<u64>,
    /// Delete replays older than this many days (0: no age limit). Default 7.
    #[arg(long, value_name = "DAYS")]
    replay_keep_days: Option<u32>,
    /// Put each frame's send time (`"sent_us"`, µs since the Unix epoch) into the
    /// frames sent live, for measuring latency on the same host (`fieldhouse loadgen`).
    #[arg(long)]
    stamp_frames: bool,
    /// Also let pages from this origin open WebSockets (scheme://host[:port], or * for
    /// any; repeatable). The server's own page always may; clients that send no Origin,
    /// like bots, are not browsers and are not checked.
    #[arg(long = "allow-origin", value_name = "ORIGIN")]
    allow_origins: Vec<String>,
    /// A host name (or address) this server is reached by, NAME or NAME:PORT
    /// (repeatable): pages served under it may open WebSockets as the server's own.
    /// Loopback names and the listen address always may; any other Host claiming to be
    /// the page's origin is refused (the shape of DNS rebinding).
    #[arg(long = "allow-host", value_name = "HOST")]
    allow_hosts: Vec<String>,
    /// Most connections (HTTP and WebSocket alike) one client address may hold open at
    /// once (default 256). At the cap its longest-idle HTTP connection (no request or
    /// response in flight: a download is busy until its last byte) is closed and the new
    /// one takes its place once it has; with none idle the new one is answered 429.
    #[arg(long, value_name = "N")]
    max_connections_per_ip: Option<usize>,
    /// Most connections in all (default: what the descriptor limit allows, less 64).
    /// Near it new spectators are refused (503) so requests and admins still get in; at
    /// it an idle connection makes room, else the new one is answered 503.
    #[arg(long, value_name = "N")]
    max_connections: Option<usize>,
    /// How long an ended match stays in the match list, seconds (default 600); at most
    /// max_matches ended matches are kept, the most recently ended.
    #[arg(long, value_name = "SECONDS")]
    ended_match_ttl_s: Option<u64>,
    /// Run as an Agones game server: say Ready to the SDK sidecar once listening, ping
    /// Health every 2 s, and ask for Shutdown (then exit) once every match has ended
    /// or on SIGTERM. Usually with --no-demo, the matches created by an allocator.
    #[arg(long)]
    agones: bool,
    /// The Agones SDK sidecar's REST port (Agones sets AGONES_SDK_HTTP_PORT).
    #[arg(
        long,
        value_name = "PORT",
        env = "AGONES_SDK_HTTP_PORT",
        default_value_t = 9358
    )]
    agones_sdk_port: u16,
    /// A TOML file of server settings (addr, max_matches, max_message_bytes,
    /// bot_messages_per_second, bot_burst, send_timeout_ms, header_timeout_ms,
    /// max_concurrent_requests, replay_retention_bytes, replay_retention_days,
    /// replay_max_match_bytes, replay_segment_bytes, ...; every setting is in the
    /// README); flags override it.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    #[command(flatten)]
    capability: CapabilityArgs,
}

pub(super) fn run(args: ServeArgs) -> anyhow::Result<()> {
    // Everything a newcomer can get wrong (settings, the admin token, a busy port) is
    // checked before motion is loaded and cost maps are built, which takes seconds, and
    // before an admin token is printed that a failed start would make useless.
    let config = settings(&args).map_err(super::bad_input)?;
    let chosen_token = admin_token_from_env().map_err(super::bad_input)?;
    if let Some(dir) = &config.replay_dir {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the replay directory {}", dir.display()))?;
    }
    let listener = listen(config.addr)?;
    let caps = args.capability.load()?;
    tracing::info!(motion = %caps.source, "motion source");
    let admin_token = match chosen_token {
        Some(t) => auth::AdminToken::chosen(t),
        None => {
            let t = auth::new_token();
            // Printed once, on the terminal only: never into the logs.
            eprintln!("admin token (set FIELDHOUSE_ADMIN_TOKEN to choose one): {t}");
            auth::AdminToken::generated(t)
        }
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::from_std(listener)?;
        let addr = listener.local_addr()?;
        tracing::info!(%addr, "listening: open http://{addr}/");
        server::serve(listener, config, admin_token, caps, shutdown_signal()).await?;
        tracing::info!("stopped");
        Ok(())
    })
}

/// The settings: defaults, then the file, then the flags; checked.
fn settings(args: &ServeArgs) -> anyhow::Result<ServerConfig> {
    let mut config = match &args.config {
        Some(path) => ServerConfig::load(path).map_err(anyhow::Error::msg)?,
        None => ServerConfig::default(),
    };
    if let Some(addr) = args.addr {
        config.addr = addr;
    }
    if args.no_demo {
        config.demo = false;
    }
    if args.stamp_frames {
        config.stamp_frames = true;
    }
    if let Some(dir) = &args.replay_dir {
        config.replay_dir = Some(dir.clone());
    }
    if let Some(bytes) = args.replay_retention_bytes {
        config.replay_retention_bytes = bytes;
    }
    if let Some(days) = args.replay_keep_days {
        config.replay_retention_days = days;
    }
    config
        .allowed_origins
        .extend(args.allow_origins.iter().cloned());
    config.agones_sdk_port = args.agones.then_some(args.agones_sdk_port);
    config
        .allowed_hosts
        .extend(args.allow_hosts.iter().cloned());
    if let Some(n) = args.max_connections_per_ip {
        config.max_connections_per_ip = n;
    }
    if let Some(n) = args.max_connections {
        config.max_connections = Some(n);
    }
    if let Some(s) = args.ended_match_ttl_s {
        config.ended_match_ttl_s = s;
    }
    config.check().map_err(anyhow::Error::msg)?;
    Ok(config)
}

/// The admin token FIELDHOUSE_ADMIN_TOKEN chooses, if it is set; one that is too short
/// to be a secret is refused.
fn admin_token_from_env() -> anyhow::Result<Option<String>> {
    match std::env::var("FIELDHOUSE_ADMIN_TOKEN") {
        Ok(t) if t.len() >= 16 => Ok(Some(t)),
        Ok(t) => anyhow::bail!(
            "FIELDHOUSE_ADMIN_TOKEN must be at least 16 characters (it has {}); \
             unset it to have one made for you",
            t.chars().count()
        ),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(_)) => {
            anyhow::bail!("FIELDHOUSE_ADMIN_TOKEN is not valid UTF-8")
        }
    }
}

/// Binds the listening socket, with a message that says what to do when it cannot.
fn listen(addr: SocketAddr) -> anyhow::Result<TcpListener> {
    let listener = TcpListener::bind(addr).map_err(|e| {
        let next = SocketAddr::new(addr.ip(), addr.port().checked_add(1).unwrap_or(0));
        let hint = match e.kind() {
            ErrorKind::AddrInUse => format!(
                "another process (another fieldhouse serve?) is listening there; pass \
                 --addr with another port, e.g. --addr {next} (port 0 takes any free one)"
            ),
            ErrorKind::PermissionDenied => format!(
                "ports below 1024 need privileges; pass --addr with another port, e.g. --addr {}",
                SocketAddr::new(addr.ip(), DEFAULT_PORT)
            ),
            ErrorKind::AddrNotAvailable => format!(
                "no interface of this machine has the address {}; pass --addr with one of \
                 its own (127.0.0.1, or 0.0.0.0 for every interface)",
                addr.ip()
            ),
            _ => "pass --addr with another address or port".to_string(),
        };
        anyhow::anyhow!("cannot listen on {addr}: {e}; {hint}")
    })?;
    // Tokio takes over a socket only in non-blocking mode.
    listener
        .set_nonblocking(true)
        .with_context(|| format!("cannot listen on {addr}"))?;
    Ok(listener)
}

/// SIGINT (Ctrl-C) or SIGTERM.
async fn shutdown_signal() {
    let interrupt = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        _ = interrupt => {}
        _ = terminate => {}
    }
}
