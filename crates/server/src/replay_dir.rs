//! The replay directory as the server sees it: which of its entries are replays, how
//! one is opened, which are being written, and the indexes their viewers share.
//!
//! Anyone who can write to the directory can put anything in it, so only a regular file
//! named `ID.jsonl.zst` (format 2, what the server writes) or `ID.jsonl` (format 1, as
//! written before), right in it, with no other name, is a replay; if both names of one
//! id are there, `ID.jsonl.zst` is the one listed and served (and the other is left
//! alone, by retention too). What a file holds is told
//! by its first bytes, not its name. A symbolic link is never followed (it could name
//! `/etc/passwd` or `/proc/self/environ`), a device or a FIFO is never read (`/dev/zero`
//! has no end, a FIFO blocks for ever), and a file with a second name (a hard link)
//! could be a file from elsewhere, so it is refused too. The checks are made on the
//! opened handle (`O_NOFOLLOW`, then `fstat`), so nothing can be swapped in between a
//! check and the open.

use fieldhouse_core::replay::{Encoding, Index};
use std::collections::{HashMap, HashSet};
use std::fs::{File, Metadata};
use std::io;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

/// Whether `id` can name a replay: letters, digits, `-` and `_` only, so no id reaches
/// outside the directory.
pub fn valid_id(id: &str) -> bool {
    !id.is_empty()
        && id.len() <= 128
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
}

/// The names of a replay file, in the order they are looked for: format 2, then 1.
const ENCODINGS: [Encoding; 2] = [Encoding::Zstd, Encoding::Plain];

/// The file a recording writes replay `id` to (`id` must be [`valid_id`]): `ID.jsonl.zst`.
pub fn path_of(dir: &Path, id: &str) -> PathBuf {
    name_of(dir, id, Encoding::Zstd)
}

fn name_of(dir: &Path, id: &str, encoding: Encoding) -> PathBuf {
    dir.join(format!("{id}.{}", encoding.extension()))
}

/// The replay id a file name gives, with the encoding its name says, if it names one.
fn id_of(name: &str) -> Option<(&str, Encoding)> {
    ENCODINGS.iter().find_map(|&e| {
        let id = name.strip_suffix(e.extension())?.strip_suffix('.')?;
        valid_id(id).then_some((id, e))
    })
}

/// Opens replay `id` for reading, if it is one: a regular file with one name, not a
/// link, named `ID.jsonl.zst` or else `ID.jsonl`. Anything else is `NotFound`, as a
/// missing file is: what else the name is, is nobody's business. The open never blocks
/// (a FIFO would).
pub fn open(dir: &Path, id: &str) -> io::Result<Found> {
    for encoding in ENCODINGS {
        let path = name_of(dir, id, encoding);
        match open_path(&path) {
            Ok((file, meta)) => {
                return Ok(Found {
                    id: id.to_string(),
                    path,
                    named: encoding,
                    file,
                    meta,
                })
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(e),
        }
    }
    Err(io::ErrorKind::NotFound.into())
}

/// Opens `path` if it is a regular file with one name, not a link (see [`open`]).
fn open_path(path: &Path) -> io::Result<(File, Metadata)> {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(|e| match e.raw_os_error() {
            // What O_NOFOLLOW answers for a link.
            Some(libc::ELOOP) => io::ErrorKind::NotFound.into(),
            _ => e,
        })?;
    let meta = file.metadata()?;
    if !meta.file_type().is_file() || meta.nlink() != 1 {
        return Err(io::ErrorKind::NotFound.into());
    }
    Ok((file, meta))
}

/// A replay found in the directory, opened.
pub struct Found {
    pub id: String,
    pub path: PathBuf,
    /// The encoding its name says; its first bytes say which it is.
    pub named: Encoding,
    pub file: File,
    pub meta: Metadata,
}

impl Found {
    /// How the file is stored, told by its first bytes; by its name if they tell
    /// nothing (it is no replay, or is empty).
    pub fn encoding(&self) -> Encoding {
        Encoding::of_file(&self.file).unwrap_or(self.named)
    }
}

/// Every replay in `dir`, opened as [`open`] opens one (one per id: the one [`open`]
/// finds); other entries are passed over without being opened. Blocking: call it on a
/// blocking thread.
pub fn scan(dir: &Path) -> Vec<Found> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        // The type of the entry itself: a link is a link, not what it points to.
        if !entry.file_type().is_ok_and(|t| t.is_file()) {
            continue;
        }
        let name = entry.file_name();
        let Some((id, named)) = name.to_str().and_then(id_of) else {
            continue;
        };
        let path = name_of(dir, id, named);
        if let Ok((file, meta)) = open_path(&path) {
            found.push(Found {
                id: id.to_string(),
                path,
                named,
                file,
                meta,
            });
        }
    }
    // Format 2's name first, so that it is the one kept of an id with both.
    let rank = |e: Encoding| ENCODINGS.iter().position(|&x| x == e);
    found.sort_by(|a, b| a.id.cmp(&b.id).then(rank(a.named).cmp(&rank(b.named))));
    found.dedup_by(|later, first| later.id == first.id);
    found
}

/// Which file an index is of: the same inode at the same size and time of change is
/// the same content (a file being written grows, and gets a new index).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Version {
    dev: u64,
    ino: u64,
    len: u64,
    mtime_ns: i128,
}

impl Version {
    fn of(meta: &Metadata) -> Version {
        Version {
            dev: meta.dev(),
            ino: meta.ino(),
            len: meta.len(),
            mtime_ns: i128::from(meta.mtime()) * 1_000_000_000 + i128::from(meta.mtime_nsec()),
        }
    }
}

/// A file, whatever its size: its device and inode.
type Inode = (u64, u64);

/// Files walked at once, at most.
const WALKS: usize = 2;

/// What the server keeps about its replay directory besides the files.
pub struct Replays {
    /// The files being written, which retention never deletes.
    pub writing: Mutex<HashSet<PathBuf>>,
    /// Bytes handed to every recording's writer and not yet written.
    pub queued: Arc<std::sync::atomic::AtomicU64>,
    /// Indexes with viewers: each file is walked once however many watch it, and its
    /// index goes when its last viewer does.
    indexes: Mutex<HashMap<Version, Weak<Index>>>,
    /// A lock per file being walked: viewers of one file arriving together wait for
    /// one walk of it, while other files are walked beside it.
    walking: Mutex<HashMap<Inode, Weak<tokio::sync::Mutex<()>>>>,
    /// How many files are walked at once: a walk reads its file once (a 1 GiB file in
    /// well under a second), so a crowd of viewers of many files costs two walks'
    /// worth of disk and CPU at a time, and no viewer waits for a walk of another file
    /// longer than that.
    walks: tokio::sync::Semaphore,
    /// What the listing said of each file, by id, while the file stays as it was: the
    /// lobby asks every 2 s, and a file unchanged since is not read again.
    listed: Mutex<HashMap<String, (Version, serde_json::Value)>>,
}

impl Default for Replays {
    fn default() -> Replays {
        Replays {
            writing: Mutex::default(),
            queued: Arc::default(),
            indexes: Mutex::default(),
            walking: Mutex::default(),
            walks: tokio::sync::Semaphore::new(WALKS),
            listed: Mutex::default(),
        }
    }
}

impl Replays {
    /// The index of an opened replay, shared with its other viewers; walked (on a
    /// blocking thread) if none has it, from where an index of the same file at an
    /// earlier size stopped if there is one.
    pub async fn index(&self, file: &File, meta: &Metadata) -> Result<Arc<Index>, String> {
        let version = Version::of(meta);
        let cached =
            |indexes: &HashMap<Version, Weak<Index>>| indexes.get(&version).and_then(Weak::upgrade);
        if let Some(index) = cached(&self.indexes.lock().expect("not poisoned")) {
            return Ok(index);
        }
        let this_file = {
            let mut walking = self.walking.lock().expect("not poisoned");
            walking.retain(|_, lock| lock.strong_count() > 0);
            let lock = walking
                .get(&(version.dev, version.ino))
                .and_then(Weak::upgrade)
                .unwrap_or_default();
            walking.insert((version.dev, version.ino), Arc::downgrade(&lock));
            lock
        };
        let _walking = this_file.lock().await;
        // Another viewer may have walked it while this one waited.
        if let Some(index) = cached(&self.indexes.lock().expect("not poisoned")) {
            return Ok(index);
        }
        // A file being written grows between viewers: walk on from an index of an
        // earlier size of it, if one is still in use, rather than from the start.
        let earlier = {
            let indexes = self.indexes.lock().expect("not poisoned");
            indexes
                .iter()
                .filter(|(v, _)| {
                    (v.dev, v.ino) == (version.dev, version.ino) && v.len < version.len
                })
                .filter_map(|(_, weak)| weak.upgrade())
                .max_by_key(|index| index.walked())
        };
        let file = file.try_clone().map_err(|e| e.to_string())?;
        let walk = move || match earlier.as_ref().and_then(|e| e.grown(&file)) {
            Some(grown) => grown,
            None => Index::build(&file),
        };
        let _permit = self.walks.acquire().await.map_err(|e| e.to_string())?;
        let index = tokio::task::spawn_blocking(walk)
            .await
            .map_err(|e| e.to_string())??;
        let index = Arc::new(index);
        let mut indexes = self.indexes.lock().expect("not poisoned");
        indexes.retain(|_, weak| weak.strong_count() > 0);
        indexes.insert(version, Arc::downgrade(&index));
        Ok(index)
    }

    /// The listing's entry for `found`: remembered while the file is unchanged, else
    /// made by `describe` (which reads the file). Entries of files gone are forgotten
    /// by [`Replays::forget_all_but`].
    pub fn listing(
        &self,
        found: &Found,
        describe: impl FnOnce() -> serde_json::Value,
    ) -> serde_json::Value {
        let version = Version::of(&found.meta);
        let known = self
            .listed
            .lock()
            .expect("not poisoned")
            .get(&found.id)
            .cloned();
        match known {
            Some((v, entry)) if v == version => entry,
            _ => {
                let entry = describe();
                let remembered = (version, entry.clone());
                self.listed
                    .lock()
                    .expect("not poisoned")
                    .insert(found.id.clone(), remembered);
                entry
            }
        }
    }

    /// Forgets the listing's entries of files not in `ids`.
    pub fn forget_all_but(&self, ids: &HashSet<&str>) {
        let mut listed = self.listed.lock().expect("not poisoned");
        listed.retain(|id, _| ids.contains(id.as_str()));
    }

    /// Whether `path` is being written.
    pub fn is_writing(&self, path: &Path) -> bool {
        self.writing.lock().expect("not poisoned").contains(path)
    }
}
