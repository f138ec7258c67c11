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
//! could be a file from elsewhere, so it is refused too.
//!
//! The directory is walked without opening its files ([`scan`]): each entry is looked
//! at with `lstat` (the entry itself, never what a link names), so a directory of
//! thousands of replays costs one descriptor to list or sweep, not one per file (when
//! every file was opened at once and held, a directory with more replays than the
//! process had descriptors was listed and swept in part, silently, and took every
//! descriptor the connections needed). A file is opened only when its content is read
//! ([`Entry::open`], [`open`]), one at a time, and the checks are made again on the
//! opened handle (`O_NOFOLLOW`, then `fstat`), so nothing can be swapped in between a
//! check and the read. Retention deletes by name, never through a handle
//! ([`Entry::remove`]): the name is looked at again just before, and `unlink` removes
//! that name only (a link, not what it points to; one name of a file with others).

use fieldhouse_core::replay::{self, Encoding, Index};
use std::collections::{HashMap, HashSet};
use std::fs::{File, Metadata};
use std::io;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

/// A replay file the server opened, as the core's readers read it: at positions, while
/// it may still grow. (The core opens and reads no file itself.)
pub struct OnDisk<'a>(pub &'a std::fs::File);

impl replay::Source for OnDisk<'_> {
    fn read_at(&self, buf: &mut [u8], at: u64) -> std::io::Result<usize> {
        std::os::unix::fs::FileExt::read_at(self.0, buf, at)
    }

    fn size(&self) -> std::io::Result<u64> {
        Ok(self.0.metadata()?.len())
    }
}

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
    /// The replay's id: its file name without the extension.
    pub id: String,
    /// Where it is.
    pub path: PathBuf,
    /// The encoding its name says; its first bytes say which it is.
    pub named: Encoding,
    /// The file, opened without following links or blocking.
    pub file: File,
    /// The opened file's metadata: a regular file with one name.
    pub meta: Metadata,
}

impl Found {
    /// How the file is stored, told by its first bytes; by its name if they tell
    /// nothing (it is no replay, or is empty).
    pub fn encoding(&self) -> Encoding {
        Encoding::of_file(&OnDisk(&self.file)).unwrap_or(self.named)
    }
}

/// A replay in the directory as its entry says (`lstat`): nothing is opened.
pub struct Entry {
    /// The replay's id: its file name without the extension.
    pub id: String,
    /// Where it is.
    pub path: PathBuf,
    /// The encoding its name says.
    pub named: Encoding,
    /// The entry's own metadata: a regular file with one name.
    pub meta: Metadata,
}

impl Entry {
    /// When it was last written, in nanoseconds since 1970: what the listing's order
    /// and retention's age go by.
    pub fn modified_ns(&self) -> i128 {
        modified_ns(&self.meta)
    }

    /// Opens it to read, as [`open`] opens a replay: the checks again, on the handle
    /// (the name may name something else since it was looked at). `NotFound` if it is
    /// gone or is no replay now.
    pub fn open(&self) -> io::Result<Found> {
        let (file, meta) = open_path(&self.path)?;
        Ok(Found {
            id: self.id.clone(),
            path: self.path.clone(),
            named: self.named,
            file,
            meta,
        })
    }

    /// Deletes it, if its name still names the file looked at (the same inode, a
    /// regular file with one name): false, and nothing deleted, if not. Nothing is
    /// opened. The name is removed, never followed: were it swapped for a link or a
    /// second name of another file between the look and the `unlink`, the link or that
    /// name would go, not what it points to, and only someone who may write the
    /// directory, and so remove the name anyway, can swap it.
    pub fn remove(&self) -> io::Result<bool> {
        let now = match std::fs::symlink_metadata(&self.path) {
            Ok(now) => now,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(false),
            Err(e) => return Err(e),
        };
        let same = now.file_type().is_file()
            && now.nlink() == 1
            && (now.dev(), now.ino()) == (self.meta.dev(), self.meta.ino());
        if !same {
            return Ok(false);
        }
        match std::fs::remove_file(&self.path) {
            Ok(()) => Ok(true),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
            Err(e) => Err(e),
        }
    }
}

/// Every replay in `dir` (one per id: the one [`open`] finds), from its directory
/// entry alone: one descriptor, the directory's, is held, and no file is opened. An
/// error reading the directory is returned, never taken for an empty or shorter one.
/// Blocking: call it on a blocking thread.
pub fn scan(dir: &Path) -> io::Result<Vec<Entry>> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name();
        let Some((id, named)) = name.to_str().and_then(id_of) else {
            continue;
        };
        // The entry itself (`fstatat` without following links): a link is a link.
        let meta = match entry.metadata() {
            Ok(meta) => meta,
            // Gone since the directory was read.
            Err(e) if e.kind() == io::ErrorKind::NotFound => continue,
            Err(e) => return Err(e),
        };
        if !meta.file_type().is_file() || meta.nlink() != 1 {
            continue;
        }
        found.push(Entry {
            id: id.to_string(),
            path: name_of(dir, id, named),
            named,
            meta,
        });
    }
    // Format 2's name first, so that it is the one kept of an id with both.
    let rank = |e: Encoding| ENCODINGS.iter().position(|&x| x == e);
    found.sort_by(|a, b| a.id.cmp(&b.id).then(rank(a.named).cmp(&rank(b.named))));
    found.dedup_by(|later, first| later.id == first.id);
    Ok(found)
}

/// When a file was last written, in nanoseconds since 1970.
fn modified_ns(meta: &Metadata) -> i128 {
    i128::from(meta.mtime()) * 1_000_000_000 + i128::from(meta.mtime_nsec())
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
            mtime_ns: modified_ns(meta),
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
    /// lobby asks every 2 s, and a file unchanged since is not opened again.
    listed: Mutex<HashMap<String, (Version, serde_json::Value)>>,
    /// Turns to walk the directory for a listing.
    listings: Arc<tokio::sync::Semaphore>,
}

/// Listings that walk the directory at once, at most; the others wait their turn
/// (without a thread). Each holds two descriptors (the directory's, and the file it
/// reads, if any) and a blocking thread: a crowd of listings costs eight descriptors,
/// well within those the server keeps from connections for files, and four threads.
pub const LISTINGS_AT_ONCE: usize = 4;

impl Default for Replays {
    fn default() -> Replays {
        Replays {
            writing: Mutex::default(),
            queued: Arc::default(),
            indexes: Mutex::default(),
            walking: Mutex::default(),
            listings: Arc::new(tokio::sync::Semaphore::new(LISTINGS_AT_ONCE)),
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
        let walk = move || match earlier.as_ref().and_then(|e| e.grown(&OnDisk(&file))) {
            Some(grown) => grown,
            None => Index::build(&OnDisk(&file)),
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

    /// A turn to walk the directory for a listing (see [`LISTINGS_AT_ONCE`]), held
    /// until the permit is dropped: moved to the blocking thread that walks, it is held
    /// as long as the walk, even if the request is gone.
    pub async fn listing_turn(&self) -> tokio::sync::OwnedSemaphorePermit {
        self.listings
            .clone()
            .acquire_owned()
            .await
            .expect("the semaphore is never closed")
    }

    /// The listing's entry for `entry`: remembered while the file is unchanged (as its
    /// `lstat` says: it is not opened), else made by `describe` from the file opened now
    /// (and closed when it returns). An error opening it is returned and nothing is
    /// remembered, so the next listing tries again; `NotFound` is a file gone, or no
    /// replay now. Entries of files gone are forgotten by [`Replays::forget_all_but`].
    pub fn listing(
        &self,
        entry: &Entry,
        describe: impl FnOnce(&Found) -> serde_json::Value,
    ) -> io::Result<serde_json::Value> {
        let version = Version::of(&entry.meta);
        let listed = |id: &str| self.listed.lock().expect("not poisoned").get(id).cloned();
        if let Some((v, known)) = listed(&entry.id) {
            if v == version {
                return Ok(known);
            }
        }
        let found = entry.open()?;
        let described = describe(&found);
        // Remembered as the file read was: it may have grown since the look.
        let remembered = (Version::of(&found.meta), described.clone());
        self.listed
            .lock()
            .expect("not poisoned")
            .insert(entry.id.clone(), remembered);
        Ok(described)
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

#[cfg(test)]
mod tests {
    use super::scan;
    use fieldhouse_core::replay::Encoding;

    fn empty_dir() -> tempfile::TempDir {
        tempfile::tempdir().unwrap()
    }

    #[test]
    fn the_walk_finds_regular_files_with_one_name_and_passes_over_the_rest() {
        let dir = empty_dir();
        let dir = dir.path();
        let outside = empty_dir();
        let outside = outside.path();
        for name in [
            "a.jsonl",
            "b.jsonl.zst",
            "both.jsonl",
            "both.jsonl.zst",
            "notes.txt",
        ] {
            std::fs::write(dir.join(name), "x").unwrap();
        }
        std::fs::write(outside.join("secret"), "x").unwrap();
        std::os::unix::fs::symlink(outside.join("secret"), dir.join("link.jsonl")).unwrap();
        std::fs::hard_link(outside.join("secret"), dir.join("hard.jsonl")).unwrap();
        std::fs::create_dir(dir.join("sub.jsonl")).unwrap();
        let found = scan(dir).unwrap();
        let ids: Vec<(&str, Encoding)> = found.iter().map(|e| (e.id.as_str(), e.named)).collect();
        assert_eq!(
            ids,
            [
                ("a", Encoding::Plain),
                ("b", Encoding::Zstd),
                ("both", Encoding::Zstd)
            ]
        );
        // A directory that cannot be read is an error, not an empty directory.
        assert!(scan(&dir.join("missing")).is_err());
    }

    /// Deleting goes by name, and only while the name still names the file weighed: a
    /// name swapped since for a link, another file or a second name of one is left.
    #[test]
    fn a_name_swapped_after_the_walk_is_not_deleted() {
        let dir = empty_dir();
        let dir = dir.path();
        let outside = empty_dir();
        let outside = outside.path();
        std::fs::write(outside.join("precious"), "keep me").unwrap();
        for name in [
            "kept.jsonl",
            "linked.jsonl",
            "hard.jsonl",
            "renewed.jsonl",
            "gone.jsonl",
        ] {
            std::fs::write(dir.join(name), "x").unwrap();
        }
        let found = scan(dir).unwrap();
        let entry = |id: &str| found.iter().find(|e| e.id == id).unwrap();
        let swap = |name: &str| std::fs::remove_file(dir.join(name)).unwrap();
        swap("linked.jsonl");
        std::os::unix::fs::symlink(outside.join("precious"), dir.join("linked.jsonl")).unwrap();
        swap("hard.jsonl");
        std::fs::hard_link(outside.join("precious"), dir.join("hard.jsonl")).unwrap();
        // A new file under the old name (the old one's inode kept alive, so that the
        // new one cannot reuse it).
        let old = std::fs::File::open(dir.join("renewed.jsonl")).unwrap();
        swap("renewed.jsonl");
        std::fs::write(dir.join("renewed.jsonl"), "new").unwrap();
        swap("gone.jsonl");
        for id in ["linked", "hard", "renewed", "gone"] {
            assert!(!entry(id).remove().unwrap(), "{id}");
        }
        drop(old);
        assert!(entry("kept").remove().unwrap());
        let mut left: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["hard.jsonl", "linked.jsonl", "renewed.jsonl"]);
        assert_eq!(
            std::fs::read_to_string(outside.join("precious")).unwrap(),
            "keep me"
        );
    }
}
