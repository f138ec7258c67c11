//! Packs the repository's motion capture (`data/mocap/<behaviour>/*.bvh`, and CMU's
//! native `*.asf` skeletons and `*.amc` motions) into one zstd stream that the binary includes (`src/motion/embedded.rs` reads it back), so every
//! command moves with real human motion with nothing beside the binary.
//!
//! The pack is a plain sequence of records, in sorted path order:
//! `u32 path length, path (UTF-8, "behaviour/file.bvh"), u64 data length, data`, all
//! little-endian. Compressing the files as one stream lets zstd share what the files have
//! in common (the same hierarchy in every file, similar rows of angles): 11.4 MB of BVH
//! text pack into about 3.4 MB at level 19, against about 4 MB file by file.
//!
//! It also tells the crate what the embedded library's source is (clip count and
//! fingerprint) without parsing it, which files of graphs and maps the repository ships
//! (`data/capability`), and a digest of the source that builds graphs and maps.

#![allow(
    clippy::disallowed_methods,
    reason = "a build script runs at compile time: it reads Cargo's environment and the repository, and writes OUT_DIR"
)]
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Level 19 is zstd's best short of its memory-hungry "ultra" levels; the pack is built
/// once per change of the data, and decompressing it takes milliseconds whatever level.
const LEVEL: i32 = 19;

fn main() {
    // The capture sits at the repository's root (`data/mocap`), two levels above this
    // crate, where users and scripts/sync-mocap find it.
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let data = root.join("../../data/mocap");
    // A directory here makes cargo rerun this script when anything under it changes: a
    // file added, removed or edited in any behaviour folder, whatever its kind.
    println!("cargo:rerun-if-changed=../../data/mocap");
    let files = motion_files(&data);
    if files.is_empty() {
        panic!(
            "no motion capture in {}: the repository carries it as data/mocap/<behaviour>/*.bvh \
             (and *.asf, *.amc; scripts/sync-mocap fills it)",
            data.display()
        );
    }
    let mut pack = Vec::new();
    for (rel, bytes) in pack_records(&data, &files) {
        pack.extend_from_slice(&(rel.len() as u32).to_le_bytes());
        pack.extend_from_slice(rel.as_bytes());
        pack.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        pack.extend_from_slice(&bytes);
    }
    source_digest(&root);
    embedded_source(&pack_records(&data, &files));
    shipped_capability(&root.join("../../data/capability"));
    let compressed = zstd::bulk::compress(&pack, LEVEL).expect("zstd compresses in memory");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo")).join("mocap.zst");
    fs::File::create(&out)
        .and_then(|mut f| f.write_all(&compressed))
        .unwrap_or_else(|e| panic!("writing {}: {e}", out.display()));
}

/// Each motion file's path under `data` ("behaviour/file.bvh") and bytes, in `files`
/// (sorted) order.
fn pack_records(data: &Path, files: &[PathBuf]) -> Vec<(String, Vec<u8>)> {
    files
        .iter()
        .map(|path| {
            let rel = path
                .strip_prefix(data)
                .expect("found under data/mocap")
                .to_str()
                .expect("motion file names are UTF-8")
                .replace('\\', "/");
            let bytes =
                fs::read(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
            (rel, bytes)
        })
        .collect()
}

/// What the embedded library's `MotionSource` says, known without parsing a clip, so
/// that a command whose graphs and maps are shipped or cached starts without reading the
/// motion at all: the clip count (every BVH and AMC file) and the fingerprint with and
/// without mirroring, computed as the loader computes it (a SHA-256 over each file's
/// length-prefixed path and bytes, in path order, after a marker when mirrored). The
/// test `embedded_source_is_known_before_parsing` holds the two to agreeing.
fn embedded_source(records: &[(String, Vec<u8>)]) {
    use sha2::{Digest, Sha256};
    let clips = records
        .iter()
        .filter(|(rel, _)| !rel.to_ascii_lowercase().ends_with(".asf"))
        .count();
    println!("cargo:rustc-env=FIELDHOUSE_EMBEDDED_CLIPS={clips}");
    // The loader orders files by their path as a string ("run-127/" before "run/"),
    // not component by component as the pack does.
    let mut records: Vec<&(String, Vec<u8>)> = records.iter().collect();
    records.sort_by(|a, b| a.0.cmp(&b.0));
    for (mirrored, var) in [(true, "MIRRORED"), (false, "PLAIN")] {
        let mut hash = Sha256::new();
        if mirrored {
            hash.update(b"mirrored");
        }
        for (rel, bytes) in &records {
            hash.update((rel.len() as u64).to_le_bytes());
            hash.update(rel.as_bytes());
            hash.update((bytes.len() as u64).to_le_bytes());
            hash.update(bytes);
        }
        let hex = hex::encode(&hash.finalize()[..8]);
        println!("cargo:rustc-env=FIELDHOUSE_EMBEDDED_FINGERPRINT_{var}={hex}");
    }
}

/// The motion graphs and cost maps the repository ships (`data/capability/*.bin.zst`,
/// written by `scripts/sync-capability`), listed by file name for
/// `costmap::cache::shipped` to include: with them the embedded motion's basketball
/// behaviours are ready the moment the binary starts, with no cache and no build.
fn shipped_capability(dir: &Path) {
    println!("cargo:rerun-if-changed=../../data/capability");
    let mut files: Vec<PathBuf> = fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.to_str().is_some_and(|s| s.ends_with(".bin.zst")))
        .collect();
    files.sort();
    let mut list = String::from("&[\n");
    for path in &files {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("UTF-8 name")
            .trim_end_matches(".zst");
        let abs = fs::canonicalize(path).expect("listed just now");
        list.push_str(&format!("    ({name:?}, include_bytes!({abs:?})),\n"));
    }
    list.push(']');
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo")).join("shipped.rs");
    fs::write(&out, list).unwrap_or_else(|e| panic!("writing {}: {e}", out.display()));
}

/// The source that decides a motion graph and its cost maps (`src/motion`,
/// `src/costmap`), digested into `FIELDHOUSE_CAPABILITY_SOURCE_DIGEST`: the cache of
/// graphs and maps keys on it, so an edit to how either is built can never be served the
/// old ones, whether or not its author remembered to bump a version.
fn source_digest(root: &Path) {
    use sha2::{Digest, Sha256};
    let mut files = Vec::new();
    for dir in ["src/motion", "src/costmap"] {
        println!("cargo:rerun-if-changed={dir}");
        rust_files(&root.join(dir), &mut files);
    }
    files.sort();
    let mut hash = Sha256::new();
    for path in &files {
        let rel = path.strip_prefix(root).expect("under the crate");
        hash.update(rel.to_string_lossy().as_bytes());
        hash.update([0]);
        // Whitespace and whole-line comments (docs included) are left out, so
        // formatting and documenting change no digest: the shipped graphs and maps
        // (data/capability) would otherwise have to be written again after either.
        let text =
            fs::read_to_string(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
        for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
            let tokens: Vec<u8> = line.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
            hash.update(tokens);
        }
        hash.update([0]);
    }
    let hex = hex::encode(&hash.finalize()[..8]);
    println!("cargo:rustc-env=FIELDHOUSE_CAPABILITY_SOURCE_DIGEST={hex}");
}

fn rust_files(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
}

/// Every `<behaviour>/*.bvh`, `*.asf` and `*.amc` under `data` (the kinds the loader
/// reads), sorted, so the pack is the same on any machine.
fn motion_files(data: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let Ok(behaviours) = fs::read_dir(data) else {
        return files;
    };
    for behaviour in behaviours.flatten().map(|e| e.path()) {
        if !behaviour.is_dir() {
            continue;
        }
        for file in fs::read_dir(&behaviour).into_iter().flatten().flatten() {
            let path = file.path();
            if path.is_file()
                && path.extension().is_some_and(|e| {
                    ["bvh", "asf", "amc"]
                        .iter()
                        .any(|kind| e.eq_ignore_ascii_case(kind))
                })
            {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}
