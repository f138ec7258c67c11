//! Running as an Agones game server (`serve --agones`): the server tells the Agones
//! SDK sidecar, through its REST API on localhost, that it is `Ready` once it listens,
//! pings `Health` every two seconds (Agones' default health check fails a server that
//! misses its 5 s period), and asks for `Shutdown` when it is done: when its matches
//! have all ended, or on SIGTERM. A fleet then replaces it with a fresh server, so each
//! allocation gets a clean process.
//!
//! The sidecar listens on `AGONES_SDK_HTTP_PORT` (9358 unless Agones says otherwise);
//! see <https://agones.dev/site/docs/guides/client-sdks/rest/>.

use super::state::AppState;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;

/// Health pings this often: well inside Agones' default 5 s period.
const HEALTH_EVERY: Duration = Duration::from_secs(2);
/// How long `Ready` is retried while the sidecar starts.
const READY_WITHIN: Duration = Duration::from_secs(30);

/// The SDK sidecar's REST API.
#[derive(Debug, Clone)]
pub struct Sdk {
    base: String,
}

impl Sdk {
    /// The SDK sidecar's HTTP API on loopback at `port` (Agones sets `AGONES_SDK_HTTP_PORT`).
    pub fn on_port(port: u16) -> Sdk {
        Sdk {
            base: format!("http://127.0.0.1:{port}"),
        }
    }

    /// POSTs `{}` to one of the SDK's verbs (`ready`, `health`, `shutdown`).
    async fn call(&self, verb: &'static str) -> Result<(), String> {
        let url = format!("{}/{verb}", self.base);
        tokio::task::spawn_blocking(move || {
            ureq::post(&url)
                .timeout(Duration::from_secs(2))
                .set("content-type", "application/json")
                .send_string("{}")
                .map(drop)
                .map_err(|e| format!("agones {verb}: {e}"))
        })
        .await
        .map_err(|e| e.to_string())?
    }

    /// Says `Ready` (retrying while the sidecar starts), then pings `Health` until
    /// `stop` turns true.
    pub async fn ready_then_healthy(self, mut stop: watch::Receiver<bool>) {
        let deadline = tokio::time::Instant::now() + READY_WITHIN;
        loop {
            match self.call("ready").await {
                Ok(()) => {
                    tracing::info!("agones: ready");
                    break;
                }
                Err(e) if tokio::time::Instant::now() < deadline => {
                    tracing::warn!(error = %e, "agones: sidecar not answering yet; retrying");
                    tokio::time::sleep(Duration::from_millis(500)).await;
                }
                Err(e) => {
                    // Agones will not allocate a server that never said Ready, and will
                    // replace it: nothing is gained by exiting first.
                    tracing::error!(error = %e, "agones: could not say ready");
                    break;
                }
            }
        }
        let mut every = tokio::time::interval(HEALTH_EVERY);
        loop {
            tokio::select! {
                _ = every.tick() => {
                    if let Err(e) = self.call("health").await {
                        tracing::warn!(error = %e, "agones: health ping failed");
                    }
                }
                changed = stop.changed() => {
                    if changed.is_err() || *stop.borrow() {
                        return;
                    }
                }
            }
        }
    }

    /// Asks Agones to shut this game server down; a failure is logged, not returned, since
    /// the server is stopping either way.
    pub async fn shutdown(&self) {
        match self.call("shutdown").await {
            Ok(()) => tracing::info!("agones: shutdown requested"),
            Err(e) => tracing::error!(error = %e, "agones: could not request shutdown"),
        }
    }
}

/// Completes once a match has run here and none runs any more: the game server's work
/// is done.
pub async fn matches_done(app: Arc<AppState>) {
    let mut every = tokio::time::interval(Duration::from_millis(250));
    loop {
        every.tick().await;
        let m = &app.metrics;
        if m.matches_created.load(Relaxed) > 0 && m.matches_running.load(Relaxed) == 0 {
            return;
        }
    }
}
