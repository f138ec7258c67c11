//! Packs the repository's motion capture (`data/mocap/<behaviour>/*.bvh`, and CMU's
//! native `*.asf` skeletons and `*.amc` motions) into one zstd stream that the binary includes (`src/motion/embedded.rs` reads it back), so every
//! command moves with real human motion with nothing beside the binary.
//!
//! The pack is a plain sequence of records, in sorted path order:
//! `u32 path length, path (UTF-8, "behaviour/file.bvh"), u64 data length, data`, all
//! little-endian. Compressing the files as one stream lets zstd share what the files have
//! in common (the same hierarchy in every file, similar rows of angles): 11.4 MB of BVH
//! text pack into about 3.4 MB at level 19, against about 4 MB file by file.

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
    for path in &files {
        let rel = path
            .strip_prefix(&data)
            .expect("found under data/mocap")
            .to_str()
            .expect("motion file names are UTF-8")
            .replace('\\', "/");
        let bytes = fs::read(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
        pack.extend_from_slice(&(rel.len() as u32).to_le_bytes());
        pack.extend_from_slice(rel.as_bytes());
        pack.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        pack.extend_from_slice(&bytes);
    }
    source_digest(&root);
    let compressed = zstd::bulk::compress(&pack, LEVEL).expect("zstd compresses in memory");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo")).join("mocap.zst");
    fs::File::create(&out)
        .and_then(|mut f| f.write_all(&compressed))
        .unwrap_or_else(|e| panic!("writing {}: {e}", out.display()));
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
        hash.update(fs::read(path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display())));
        hash.update([0]);
    }
    let hex: String = hash.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
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
