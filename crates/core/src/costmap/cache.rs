//! Cost maps cached on disk, keyed by everything that decides them: the motion data's
//! fingerprint, the behaviour, the graph itself (a digest of its nodes and edges, so a
//! change to how graphs are built can never be served stale maps) and its parameters,
//! the build parameters, and the code version.
//!
//! A map is written to a temporary file, synced, then renamed into place, so an
//! interrupted build never leaves a half-written map behind; a file that does not parse
//! (corrupt, or from an older format) is ignored and rebuilt.

use super::{BuildParams, CostMap};
use crate::motion::{GraphParams, MotionGraph};
use serde::Serialize;
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Bump when the meaning of a cached map changes without the crate version changing
/// (3: `search` follows every short walk from the start exactly, so its maps improved;
/// 4: graphs keep every clip, without the jump shots; 5: search splits at choices only
/// and adds random walks near the start).
const CACHE_FORMAT: u32 = 5;

#[derive(Serialize)]
struct Key<'a> {
    format: u32,
    version: &'static str,
    motion: &'a str,
    behaviour: &'a str,
    graph: &'a GraphParams,
    graph_digest: String,
    build: &'a BuildParams,
    starts: &'a [u32],
    search: (usize, usize),
}

/// The file the maps of `graph` with these inputs live in under `dir`.
pub fn path_for(
    dir: &Path,
    motion_fingerprint: &str,
    graph: &MotionGraph,
    build: &BuildParams,
    starts: &[u32],
) -> PathBuf {
    let behaviour = graph.behaviour.as_str();
    let key = Key {
        format: CACHE_FORMAT,
        version: env!("CARGO_PKG_VERSION"),
        motion: motion_fingerprint,
        behaviour,
        graph: &graph.params,
        graph_digest: graph.digest(),
        build,
        starts,
        search: (build.search.heading_bins, build.search.sub_cells),
    };
    let digest = Sha256::digest(serde_json::to_vec(&key).expect("keys serialise"));
    let hex: String = digest[..8].iter().map(|b| format!("{b:02x}")).collect();
    let safe: String = behaviour
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    dir.join(format!("costmap-{safe}-{}-{hex}.json", build.method.name()))
}

/// The default cache directory: `$XDG_CACHE_HOME/fieldhouse`, else `~/.cache/fieldhouse`.
pub fn default_dir() -> Option<PathBuf> {
    std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
        .map(|d| d.join("fieldhouse"))
}

/// The maps of `graph` with `params` from each of `starts` (nodes): read from the cache
/// under `dir` if it holds them, else built (telling `progress` 0 as it starts, then as
/// [`CostMap::build`] does) and stored there. A cache that cannot be written is logged
/// and otherwise ignored: the maps are still good. Returns the maps and whether they came
/// from the cache.
pub fn build_or_load(
    dir: Option<&Path>,
    motion_fingerprint: &str,
    graph: &MotionGraph,
    params: &BuildParams,
    starts: &[u32],
    progress: &mut dyn FnMut(u64),
) -> (Vec<CostMap>, bool) {
    let file = dir.map(|d| path_for(d, motion_fingerprint, graph, params, starts));
    if let Some(maps) = file.as_deref().and_then(load) {
        if maps.len() == starts.len() {
            return (maps, true);
        }
    }
    progress(0);
    let maps = CostMap::build_from(graph, params, starts, progress);
    if let Some(file) = &file {
        if let Err(e) = store(file, &maps) {
            tracing::warn!(file = %file.display(), error = %e, "could not cache the cost maps");
        }
    }
    (maps, false)
}

/// The cached maps at `path`, if there is a readable file of them.
pub fn load(path: &Path) -> Option<Vec<CostMap>> {
    let bytes = std::fs::read(path).ok()?;
    match serde_json::from_slice(&bytes) {
        Ok(maps) => Some(maps),
        Err(e) => {
            tracing::warn!(path = %path.display(), error = %e, "ignoring an unreadable cached cost map");
            None
        }
    }
}

/// Writes `maps` to `path` atomically (temporary file, sync, rename).
pub fn store(path: &Path, maps: &[CostMap]) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(&serde_json::to_vec(maps).map_err(std::io::Error::other)?)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::costmap::Method;
    use crate::fixtures;

    #[test]
    fn a_map_round_trips_and_the_key_follows_every_input() {
        let dir = std::env::temp_dir().join(format!("fieldhouse-cache-{}", std::process::id()));
        let graph = fixtures::graph();
        let params = BuildParams {
            method: Method::Search,
            grid: crate::costmap::Grid::new(6.0, 0.5),
            depth: 30,
            ..BuildParams::default()
        };
        let map = CostMap::build(&graph, &params, &mut |_| {});
        let path = path_for(&dir, "abc", &graph, &params, &[3]);
        assert!(load(&path).is_none());
        store(&path, std::slice::from_ref(&map)).unwrap();
        let back = load(&path).unwrap().pop().unwrap();
        assert_eq!(back.costs, map.costs);
        assert_eq!(back.paths, map.paths);
        assert_ne!(path_for(&dir, "abc", &graph, &params, &[4]), path);
        // Any change of input gives another file.
        let other = BuildParams {
            depth: 31,
            ..params.clone()
        };
        assert_ne!(path_for(&dir, "abc", &graph, &other, &[3]), path);
        assert_ne!(path_for(&dir, "abd", &graph, &params, &[3]), path);
        // So does another graph with the same parameters (here, one clip fewer).
        let clips = fixtures::library();
        let fewer: Vec<&crate::motion::Clip> = clips.iter().skip(1).collect();
        let smaller = MotionGraph::build("run", &fewer, graph.params).unwrap();
        assert_ne!(path_for(&dir, "abc", &smaller, &params, &[3]), path);
        // A corrupt file is ignored, not trusted.
        std::fs::write(&path, b"{\"method\": \"mc\", \"costs\": [1, 2").unwrap();
        assert!(load(&path).is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
