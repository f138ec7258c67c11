//! Ended matches leave the table. A match is listed (and can be shown) for
//! `ended_match_ttl_s` after it ends so clients can read its result, and at most
//! `max_matches` ended matches are kept at once, the most recently ended. Without this a
//! burst of fast matches stayed listed until someone deleted each one: 538 entries, a
//! 1.38 MB `GET /api/matches`. So the table holds at most `max_matches` running plus
//! `max_matches` ended matches.

use super::state::AppState;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;

/// How often expired matches are looked for: an ended match is listed at most this
/// much longer than its time to live.
pub const EVERY: Duration = Duration::from_secs(1);

/// Removes ended matches past their time to live, then the longest-ended beyond
/// `max_matches` of them. Returns how many it removed.
pub fn sweep(app: &AppState, now: Instant) -> usize {
    let ttl = Duration::from_secs(app.config.ended_match_ttl_s);
    let mut matches = app.matches.write().expect("not poisoned");
    let before = matches.len();
    matches.retain(|_, m| {
        !m.ended.load(Relaxed)
            || m.ended_at
                .get()
                .is_none_or(|&at| now.duration_since(at) < ttl)
    });
    let mut ended: Vec<(Instant, String)> = matches
        .iter()
        .filter_map(|(id, m)| m.ended_at.get().map(|&at| (at, id.clone())))
        .collect();
    if ended.len() > app.config.max_matches {
        ended.sort();
        let excess = ended.len() - app.config.max_matches;
        for (_, id) in &ended[..excess] {
            matches.remove(id);
        }
    }
    before - matches.len()
}

/// Sweeps every [`EVERY`] until the server shuts down.
pub async fn run(app: Arc<AppState>) {
    let mut shutdown = app.shutdown.clone();
    let mut every = tokio::time::interval(EVERY);
    loop {
        tokio::select! {
            _ = shutdown.changed() => return,
            _ = every.tick() => {
                let removed = sweep(&app, Instant::now());
                if removed > 0 {
                    tracing::debug!(removed, "ended matches expired");
                }
            }
        }
    }
}
