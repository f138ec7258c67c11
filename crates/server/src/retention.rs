//! Retention: the replay directory stays under `replay_retention_bytes` in all and
//! keeps nothing older than `replay_retention_days`. A sweep deletes the oldest replays
//! (by the time each was last written) first until both hold; it never deletes a file
//! being written (the limit is then exceeded until that file is done) and never touches
//! what is not a replay (links, devices, other names: see [`super::replay_dir`]).
//!
//! A sweep needs only sizes and times, so it opens no replay: it walks the directory
//! with `lstat` (one descriptor, the directory's, whatever the number of files), and
//! deletes by name, each name looked at again just before (see
//! [`replay_dir::Entry::remove`]). It costs one `lstat` per replay: 2,000 replays take a
//! few milliseconds. When every file was opened and held for a sweep, a directory with
//! more replays than the process had descriptors was weighed in part and not kept to
//! its limit.
//!
//! Sweeps run on a blocking thread, one at a time: at start, every minute, and after
//! recordings finish, but at most once a second ([`MIN_GAP`]): a recording that
//! finishes asks for one, and a burst of them (demo segments rotating, matches created
//! and deleted in a loop) is taken by one sweep, where each asked for its own before.

use super::replay_dir;
use super::state::AppState;
use std::io;
use std::path::Path;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime};

/// How often the directory is looked at, besides when a recording finishes.
const EVERY: Duration = Duration::from_secs(60);

/// The least time from the start of one sweep to the start of the next.
pub const MIN_GAP: Duration = Duration::from_secs(1);

/// The limits a sweep keeps.
#[derive(Debug, Clone, Copy)]
pub struct Keep {
    /// The most bytes the finished replays may take together.
    pub bytes: u64,
    /// None: no age limit.
    pub age: Option<Duration>,
}

/// Deletes the oldest replays in `dir` that are not being written until the rest fit
/// `keep`, without opening any; `deleted` is told of each as it goes (its id and size).
/// Returns how many went; an error walking the directory is returned (nothing is
/// deleted then). Blocking.
pub fn sweep(
    dir: &Path,
    keep: Keep,
    writing: impl Fn(&Path) -> bool,
    mut deleted: impl FnMut(&str, u64),
) -> io::Result<usize> {
    let mut found = replay_dir::scan(dir)?;
    let mut total: u64 = found.iter().map(|f| f.meta.len()).sum();
    // The oldest first; by id among files of the same time, so a sweep is repeatable.
    found.sort_by(|a, b| {
        a.modified_ns()
            .cmp(&b.modified_ns())
            .then_with(|| a.id.cmp(&b.id))
    });
    let now = SystemTime::now();
    let modified = |f: &replay_dir::Entry| f.meta.modified().unwrap_or(SystemTime::UNIX_EPOCH);
    let mut gone = 0;
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
        let bytes = f.meta.len();
        match f.remove() {
            Ok(true) => {
                total -= bytes;
                gone += 1;
                deleted(&f.id, bytes);
            }
            // Gone, or its name names another file now: weighed again next sweep.
            Ok(false) => {}
            Err(e) => tracing::warn!(id = %f.id, error = %e, "cannot delete an old replay"),
        }
    }
    Ok(gone)
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
        let started = Instant::now();
        let (app2, dir2) = (app.clone(), dir.clone());
        let swept = tokio::task::spawn_blocking(move || {
            let writing = |p: &Path| app2.replays.is_writing(p);
            // Counted and logged as each goes, not once the sweep is over.
            sweep(&dir2, keep, writing, |id, bytes| {
                app2.metrics.replays_deleted.fetch_add(1, Relaxed);
                tracing::info!(%id, bytes, "deleted an old replay (retention)");
            })
        })
        .await;
        app.metrics.replay_sweeps.fetch_add(1, Relaxed);
        match swept {
            Ok(Ok(_)) => {}
            Ok(Err(e)) => {
                tracing::warn!(error = %e, "cannot read the replay directory to keep it to its limits")
            }
            Err(e) => tracing::warn!(error = %e, "a retention sweep failed"),
        }
        tracing::debug!(took = ?started.elapsed(), "retention sweep");
        // A recording that finishes during the sweep or the gap leaves a permit
        // (`notify_one`): however many finish, the next sweep takes them all.
        tokio::select! {
            _ = tokio::time::sleep(EVERY) => {}
            _ = app.replay_written.notified() => {}
            _ = stopping.changed() => return,
        }
        tokio::select! {
            _ = tokio::time::sleep_until((started + MIN_GAP).into()) => {}
            _ = stopping.changed() => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{sweep, Keep};
    use std::path::Path;
    use std::time::{Duration, SystemTime};

    /// Writes `bytes` bytes to `dir/name`, last written `ago` before now.
    fn replay(dir: &Path, name: &str, bytes: usize, ago: Duration) {
        let file = std::fs::File::create(dir.join(name)).unwrap();
        std::io::Write::write_all(&mut &file, &vec![b'x'; bytes]).unwrap();
        file.set_modified(SystemTime::now() - ago).unwrap();
    }

    #[test]
    fn a_sweep_deletes_the_oldest_first_down_to_its_limits_by_name_alone() {
        let scratch = tempfile::tempdir().unwrap();
        let dir = scratch.path().to_path_buf();
        std::fs::create_dir_all(dir.join("outside")).unwrap();
        let day = Duration::from_secs(86_400);
        replay(&dir, "ancient.jsonl", 10, day * 30);
        replay(&dir, "old.jsonl.zst", 100, day * 3);
        replay(&dir, "writing.jsonl.zst", 100, day * 2);
        replay(&dir, "middle.jsonl", 100, day);
        replay(&dir, "new.jsonl.zst", 100, Duration::ZERO);
        // A link older than all, to a file outside: neither goes.
        replay(&dir.join("outside"), "precious.jsonl", 1000, day * 100);
        std::os::unix::fs::symlink(dir.join("outside/precious.jsonl"), dir.join("link.jsonl"))
            .unwrap();
        let keep = Keep {
            bytes: 250,
            age: Some(day * 10),
        };
        let writing = |p: &Path| p.ends_with("writing.jsonl.zst");
        let mut deleted = Vec::new();
        let gone = sweep(&dir, keep, writing, |id, bytes| {
            deleted.push((id.to_string(), bytes))
        })
        .unwrap();
        // ancient for its age; old and middle for the size (410, 400, 300, 200 bytes).
        assert_eq!(gone, 3);
        let deleted: Vec<(&str, u64)> = deleted.iter().map(|(i, b)| (i.as_str(), *b)).collect();
        assert_eq!(deleted, [("ancient", 10), ("old", 100), ("middle", 100)]);
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            [
                "link.jsonl",
                "new.jsonl.zst",
                "outside",
                "writing.jsonl.zst"
            ]
        );
        assert!(dir.join("outside/precious.jsonl").exists());
        assert!(sweep(&dir.join("missing"), keep, writing, |_, _| {}).is_err());
    }
}
