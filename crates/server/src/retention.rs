//! Retention: the replay directory stays under `replay_retention_bytes` in all and
//! keeps nothing older than `replay_retention_days`. A sweep deletes the oldest replays
//! first until both hold; it never deletes a file being written (the limit is then
//! exceeded until that file is done) and never touches what is not a replay (links,
//! devices, other names: see [`super::replay_dir`]). It runs at start, every minute,
//! and whenever a recording finishes, on a blocking thread.

use super::replay_dir;
use super::state::AppState;
use std::path::Path;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::{Duration, SystemTime};

/// How often the directory is looked at, besides when a recording finishes.
const EVERY: Duration = Duration::from_secs(60);

/// The limits a sweep keeps.
#[derive(Debug, Clone, Copy)]
pub struct Keep {
    pub bytes: u64,
    /// None: no age limit.
    pub age: Option<Duration>,
}

/// A replay deleted: its id and size.
pub type Deleted = (String, u64);

/// Deletes the oldest replays in `dir` that are not being written until the rest fit
/// `keep`. Blocking.
pub fn sweep(dir: &Path, keep: Keep, writing: impl Fn(&Path) -> bool) -> Vec<Deleted> {
    let mut found = replay_dir::scan(dir);
    let mut total: u64 = found.iter().map(|f| f.meta.len()).sum();
    let modified = |f: &replay_dir::Found| f.meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
    found.sort_by_key(modified);
    let now = SystemTime::now();
    let mut deleted = Vec::new();
    for f in found {
        let too_old = keep
            .age
            .is_some_and(|age| now.duration_since(modified(&f)).unwrap_or_default() > age);
        if total <= keep.bytes && !too_old {
            continue;
        }
        if writing(&f.path) {
            continue;
        }
        // Only the name that was opened and checked: a name swapped for a link since
        // loses the link, never what it points to.
        match std::fs::remove_file(&f.path) {
            Ok(()) => {
                total -= f.meta.len();
                deleted.push((f.id, f.meta.len()));
            }
            Err(e) => tracing::warn!(id = %f.id, error = %e, "cannot delete an old replay"),
        }
    }
    deleted
}

/// Sweeps the server's replay directory, if it has one, until the server stops.
pub async fn run(app: Arc<AppState>) {
    let Some(dir) = app.replay_dir.clone() else {
        return;
    };
    let config = &app.config;
    let keep = Keep {
        bytes: config.replay_retention_bytes,
        age: (config.replay_retention_days > 0)
            .then(|| Duration::from_secs(u64::from(config.replay_retention_days) * 86_400)),
    };
    let mut stopping = app.shutdown.clone();
    loop {
        let (app2, dir2) = (app.clone(), dir.clone());
        let swept =
            tokio::task::spawn_blocking(move || sweep(&dir2, keep, |p| app2.replays.is_writing(p)))
                .await
                .unwrap_or_default();
        for (id, bytes) in swept {
            app.metrics.replays_deleted.fetch_add(1, Relaxed);
            tracing::info!(%id, bytes, "deleted an old replay (retention)");
        }
        tokio::select! {
            _ = tokio::time::sleep(EVERY) => {}
            _ = app.replay_written.notified() => {}
            _ = stopping.changed() => return,
        }
    }
}
