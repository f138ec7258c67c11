//! A behaviour's motion graph and its cost maps, cached together, keyed by
//! everything that decides them: the motion data's fingerprint, the behaviour, the
//! windows the automatic graph choice tries, the build parameters, the crate version and
//! a digest of the source that builds graphs and maps (`build.rs`), so that no change to
//! how they are made can ever be served stale ones.
//!
//! **The file** is binary and checked: an 8-byte magic, the format version (u32), the
//! payload's length (u64) and its SHA-256, then the payload ([`postcard`]: the graph,
//! then the maps). A file that is not a cache, is of another format, is cut short, fails
//! its checksum or does not decode is refused with a message saying which, logged, and
//! rebuilt. Where files are kept is the edge's [`Store`] (the CLI's cache directory
//! writes each to a temporary file, synced, then renamed into place, so an interrupted
//! build never leaves half a file behind); this module only names, encodes and checks
//! them.
//!
//! **Shipped files.** The graphs and maps of the embedded motion's basketball behaviours
//! are a pure function of the capture and the code, so the repository carries them
//! (`data/capability/<file name>.zst`, written by `scripts/sync-capability`) and the
//! binary includes them: a first start builds nothing. They are found by the same file
//! name a cache would use, so a change of anything that decides them (the source digest
//! among it) simply misses them and builds, and the test
//! `the_shipped_graphs_and_maps_are_what_the_code_builds` fails until they are written
//! again.

use super::CostMap;
use crate::motion::{Jump, MotionGraph, TurnAround};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use thiserror::Error;

/// Bump when the file's layout or the meaning of what it holds changes in a way the
/// source digest cannot see (6: binary, the graph beside its maps; 7: the turn around
/// and the jumps beside them).
pub const CACHE_FORMAT: u32 = 7;

/// What every cache file starts with.
const MAGIC: &[u8; 8] = b"fhcache\n";
/// Magic, format, payload length, SHA-256.
const HEADER_BYTES: usize = 8 + 4 + 8 + 32;

/// The source files that build graphs and maps, digested by `build.rs`.
const SOURCE_DIGEST: &str = env!("FIELDHOUSE_CAPABILITY_SOURCE_DIGEST");

/// What a cache file holds: a behaviour's graph and its maps, one per start state, and
/// what else is slow to measure on them and fixed once they are (for the capability
/// report: the quickest turn around, the jump shots cut from the clips).
#[derive(Debug, Serialize, Deserialize)]
pub struct Cached {
    /// The motion graph.
    pub graph: MotionGraph,
    /// Its cost maps.
    pub maps: Vec<CostMap>,
    /// The quickest turn around from the stance (`None`: none found, or not measured,
    /// as for a map of a chosen start alone).
    pub turn: Option<TurnAround>,
    /// The jump shots found in the behaviour's clips, by clip (cut from the graph).
    pub jumps: Vec<ClipJump>,
}

/// A jump shot and the clip it is in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClipJump {
    /// The clip's name.
    pub clip: String,
    /// Where in it the jump is.
    pub jump: Jump,
}

/// The graphs and maps the repository ships, by file name (see `build.rs`).
static SHIPPED: &[(&str, &[u8])] = include!(concat!(env!("OUT_DIR"), "/shipped.rs"));

/// Where cache files are kept between runs, by file name. The core has no file system:
/// the edge hands one in (the CLI's cache directory, written atomically).
pub trait Store {
    /// The bytes kept as `name`, or `None` if there are none.
    fn load(&self, name: &str) -> std::io::Result<Option<Vec<u8>>>;
    /// Keeps `bytes` as `name`, whole or not at all.
    fn keep(&self, name: &str, bytes: &[u8]) -> std::io::Result<()>;
}

/// Where [`build_or_load`] may find a behaviour's graph and maps before it builds them.
#[derive(Clone, Copy)]
pub enum Reuse<'a> {
    /// Nowhere: build, and store nothing (to measure a build, or to check one).
    Nothing,
    /// The files shipped in the binary; no cache (none was found).
    Shipped,
    /// The files shipped in the binary, else this cache, where whatever is built is
    /// kept.
    ShippedOrStore(&'a dyn Store),
}

/// Where a graph and its maps came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// Shipped in the binary.
    Shipped,
    /// Read from the cache directory.
    Cache,
    /// Built just now.
    Built,
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Origin::Shipped => "shipped with fieldhouse",
            Origin::Cache => "read from the cache",
            Origin::Built => "built",
        })
    }
}

/// Why a cache file was not used.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum CacheError {
    /// It does not start with the magic.
    #[error("not a fieldhouse cache file")]
    Foreign,
    /// It ends inside its header.
    #[error("cut short inside its header ({actual} of {HEADER_BYTES} bytes)")]
    Header {
        /// Bytes the file has.
        actual: usize,
    },
    /// Another format version wrote it.
    #[error("cache format {found}; this build reads format {CACHE_FORMAT}")]
    Format {
        /// The file's.
        found: u32,
    },
    /// Fewer (or more) bytes than its header says.
    #[error("{actual} bytes of payload where the header says {declared}: cut short or padded")]
    Length {
        /// What the header says.
        declared: u64,
        /// What the file has.
        actual: u64,
    },
    /// The payload is not what was written.
    #[error("corrupt: the payload's SHA-256 does not match the header's")]
    Checksum,
    /// The payload does not decode, or decodes into parts that do not fit together
    /// (a writer's bug, or a hostile file, as the checksum held).
    #[error("the payload does not decode: {0}")]
    Decode(String),
}

#[derive(Serialize)]
struct Key<'a, I> {
    format: u32,
    version: &'static str,
    source: &'static str,
    motion: &'a str,
    behaviour: &'a str,
    inputs: &'a I,
}

/// The name of the file that holds the graph and maps of `behaviour` for the motion data
/// `motion_fingerprint` and `inputs`: `capability-<behaviour>-<16 hex digits of the key>.bin`.
pub fn file_name(motion_fingerprint: &str, behaviour: &str, inputs: &impl Serialize) -> String {
    let key = Key {
        format: CACHE_FORMAT,
        version: env!("CARGO_PKG_VERSION"),
        source: SOURCE_DIGEST,
        motion: motion_fingerprint,
        behaviour,
        inputs,
    };
    let digest = Sha256::digest(serde_json::to_vec(&key).expect("keys serialise"));
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    let safe: String = behaviour
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("capability-{safe}-{hex}.bin")
}

/// The graph and maps of `behaviour`: shipped in the binary or read from the cache, as
/// `reuse` allows, if either holds them; else made by `build` and kept in the cache. A
/// cache that cannot be read or written is logged and otherwise ignored: what `build`
/// makes is still good. Returns them and where they came from.
pub fn build_or_load<E>(
    reuse: Reuse<'_>,
    motion_fingerprint: &str,
    behaviour: &str,
    inputs: &impl Serialize,
    build: impl FnOnce() -> Result<Cached, E>,
) -> Result<(Cached, Origin), E> {
    let name = file_name(motion_fingerprint, behaviour, inputs);
    let store = match reuse {
        Reuse::Nothing => None,
        Reuse::Shipped | Reuse::ShippedOrStore(_) => {
            if let Some(cached) = shipped(&name) {
                return Ok((cached, Origin::Shipped));
            }
            match reuse {
                Reuse::ShippedOrStore(store) => Some(store),
                _ => None,
            }
        }
    };
    if let Some(store) = store {
        match store.load(&name) {
            Ok(Some(bytes)) => match decode(&bytes) {
                Ok(cached) => return Ok((cached, Origin::Cache)),
                Err(e) => tracing::warn!(
                    file = name,
                    error = %e,
                    "ignoring a cached motion graph and its cost maps, and rebuilding them"
                ),
            },
            Ok(None) => {}
            Err(e) => tracing::warn!(file = name, error = %e, "cannot read the cache"),
        }
    }
    let cached = build()?;
    if let Some(store) = store {
        if let Err(e) = store.keep(&name, &encode(&cached)) {
            tracing::warn!(file = name, error = %e, "could not cache the cost maps");
        }
    }
    Ok((cached, Origin::Built))
}

/// The shipped graph and maps of file `name`, if the binary carries it.
pub fn shipped(name: &str) -> Option<Cached> {
    let (_, compressed) = SHIPPED.iter().find(|(shipped, _)| *shipped == name)?;
    // The repository's own files, checked by the test suite: a failure here is a build
    // defect, and building instead is still correct.
    match zstd::decode_all(*compressed)
        .map_err(|e| CacheError::Decode(format!("zstd: {e}")))
        .and_then(|bytes| decode(&bytes))
    {
        Ok(cached) => Some(cached),
        Err(e) => {
            tracing::error!(file = name, error = %e, "a shipped motion graph and its cost maps do not read; building them");
            None
        }
    }
}

/// The file names the binary ships.
pub fn shipped_names() -> impl Iterator<Item = &'static str> {
    SHIPPED.iter().map(|(name, _)| *name)
}

/// A cache file's bytes.
pub fn encode(cached: &Cached) -> Vec<u8> {
    let payload = postcard::to_stdvec(cached).expect("graphs and maps serialise");
    let mut bytes = Vec::with_capacity(HEADER_BYTES + payload.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&CACHE_FORMAT.to_le_bytes());
    bytes.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&Sha256::digest(&payload));
    bytes.extend_from_slice(&payload);
    bytes
}

/// What a cache file holds, or why it cannot be used. Any bytes are safe to give it:
/// nothing is decoded before the length and checksum hold, and decoding allocates no
/// more than the payload could describe.
pub fn decode(bytes: &[u8]) -> Result<Cached, CacheError> {
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(CacheError::Foreign);
    }
    if bytes.len() < HEADER_BYTES {
        return Err(CacheError::Header {
            actual: bytes.len(),
        });
    }
    let found = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if found != CACHE_FORMAT {
        return Err(CacheError::Format { found });
    }
    let declared = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER_BYTES..];
    if declared != payload.len() as u64 {
        return Err(CacheError::Length {
            declared,
            actual: payload.len() as u64,
        });
    }
    if Sha256::digest(payload).as_slice() != &bytes[20..52] {
        return Err(CacheError::Checksum);
    }
    decode_payload(payload)
}

/// The graph and maps in a payload, checked to fit together (every index in range), so
/// that nothing read from a file can make a later lookup fail.
pub fn decode_payload(payload: &[u8]) -> Result<Cached, CacheError> {
    let cached: Cached =
        postcard::from_bytes(payload).map_err(|e| CacheError::Decode(e.to_string()))?;
    cached.graph.check().map_err(CacheError::Decode)?;
    if let Some(turn) = &cached.turn {
        if turn
            .nodes
            .iter()
            .any(|&n| n as usize >= cached.graph.node_count())
        {
            return Err(CacheError::Decode(
                "the turn around plays a node the graph does not have".into(),
            ));
        }
    }
    for (i, map) in cached.maps.iter().enumerate() {
        map.check(&cached.graph)
            .map_err(|e| CacheError::Decode(format!("map {i}: {e}")))?;
    }
    Ok(cached)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::costmap::{BuildParams, Method};
    use crate::fixtures;

    fn cached() -> (Cached, BuildParams) {
        let graph = fixtures::graph();
        let params = BuildParams {
            method: Method::Search,
            grid: crate::costmap::Grid::new(6.0, 0.5),
            depth: 30,
            ..BuildParams::default()
        };
        let map = CostMap::build(&graph, &params, &mut |_| {});
        (
            Cached {
                graph,
                maps: vec![map],
                turn: None,
                jumps: Vec::new(),
            },
            params,
        )
    }

    #[test]
    fn the_graph_and_its_maps_round_trip_and_the_key_follows_every_input() {
        let (cached, params) = cached();
        let name = file_name("abc", "run", &([10, 8], &params));
        let back = decode(&encode(&cached)).unwrap();
        assert_eq!(back.graph.digest(), cached.graph.digest());
        assert_eq!(back.maps[0].costs, cached.maps[0].costs);
        assert_eq!(back.maps[0].paths, cached.maps[0].paths);
        // Any change of input gives another file.
        let deeper = BuildParams {
            depth: 31,
            ..params.clone()
        };
        for other in [
            file_name("abd", "run", &([10, 8], &params)),
            file_name("abc", "dribble", &([10, 8], &params)),
            file_name("abc", "run", &([10], &params)),
            file_name("abc", "run", &([10, 8], &deeper)),
        ] {
            assert_ne!(other, name);
        }
    }

    #[test]
    fn a_foreign_cut_corrupt_or_older_file_is_refused_saying_which() {
        let (cached, _) = cached();
        let good = encode(&cached);
        assert_eq!(
            decode(b"{\"method\": \"mc\"}").unwrap_err(),
            CacheError::Foreign
        );
        let cut = &good[..good.len() - 1];
        assert!(matches!(decode(cut), Err(CacheError::Length { .. })));
        assert_eq!(
            decode(&good[..10]).unwrap_err().to_string(),
            "cut short inside its header (10 of 52 bytes)"
        );
        let mut flipped = good.clone();
        let last = flipped.len() - 1;
        flipped[last] ^= 1;
        assert_eq!(decode(&flipped).unwrap_err(), CacheError::Checksum);
        let mut older = good.clone();
        older[8..12].copy_from_slice(&5u32.to_le_bytes());
        assert_eq!(decode(&older).unwrap_err(), CacheError::Format { found: 5 });
        // A payload whose checksum holds but which is not a graph and maps.
        let junk = b"not postcard at all";
        let mut forged = Vec::new();
        forged.extend_from_slice(MAGIC);
        forged.extend_from_slice(&CACHE_FORMAT.to_le_bytes());
        forged.extend_from_slice(&(junk.len() as u64).to_le_bytes());
        forged.extend_from_slice(&Sha256::digest(junk));
        forged.extend_from_slice(junk);
        assert!(matches!(decode(&forged), Err(CacheError::Decode(_))));
        assert!(decode(&good).is_ok());
    }

    /// A cache in memory.
    #[derive(Default)]
    struct Memory(std::cell::RefCell<std::collections::HashMap<String, Vec<u8>>>);

    impl Store for Memory {
        fn load(&self, name: &str) -> std::io::Result<Option<Vec<u8>>> {
            Ok(self.0.borrow().get(name).cloned())
        }
        fn keep(&self, name: &str, bytes: &[u8]) -> std::io::Result<()> {
            self.0.borrow_mut().insert(name.to_owned(), bytes.to_vec());
            Ok(())
        }
    }

    #[test]
    fn a_refused_file_is_rebuilt_and_replaced() {
        let store = Memory::default();
        let (cached, params) = cached();
        let name = file_name("abc", "run", &params);
        store.keep(&name, b"fhcache\ngarbage").unwrap();
        let mut builds = 0;
        let mut build = || {
            builds += 1;
            Ok::<_, ()>(Cached {
                graph: cached.graph.clone(),
                maps: cached.maps.clone(),
                turn: None,
                jumps: Vec::new(),
            })
        };
        let reuse = Reuse::ShippedOrStore(&store);
        let (_, origin) = build_or_load(reuse, "abc", "run", &params, &mut build).unwrap();
        assert_eq!(origin, Origin::Built);
        assert!(
            decode(&store.load(&name).unwrap().unwrap()).is_ok(),
            "replaced"
        );
        let (_, origin) = build_or_load(reuse, "abc", "run", &params, &mut build).unwrap();
        assert_eq!(origin, Origin::Cache);
        // Nothing: neither read nor kept.
        let (_, origin) = build_or_load(Reuse::Nothing, "abc", "run", &params, &mut build).unwrap();
        assert_eq!(origin, Origin::Built);
        assert_eq!(builds, 2);
    }
}
