//! The graphs and maps the repository ships (`data/capability`) are exactly what the
//! code builds from the embedded motion: byte for byte, for each basketball behaviour.
//!
//! They are found by the file name a cache would use, which digests the motion, the
//! build parameters and the source that builds them, so after a change to any of these
//! this test fails (the file is missing or differs) until they are written again:
//!
//! ```text
//! scripts/sync-capability
//! ```
//!
//! which runs this test with `FIELDHOUSE_BLESS=1`: it then writes the files
//! (zstd level 19) and removes the ones they replace.

#![allow(
    clippy::disallowed_methods,
    reason = "a test reads the shipped files and its bless switch"
)]
use fieldhouse_core::basketball::Mover;
use fieldhouse_core::costmap::cache;
use fieldhouse_core::motion::{Mirroring, MotionLibrary, FPS};
use std::path::{Path, PathBuf};

const BEHAVIOURS: [&str; 3] = ["dribble", "run", "defense"];

fn shipped_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/capability")
}

#[test]
fn the_shipped_graphs_and_maps_are_what_the_code_builds() {
    let library = MotionLibrary::embedded(FPS, Mirroring::On);
    let write = std::env::var_os("FIELDHOUSE_BLESS").is_some_and(|v| v == "1");
    let mut stale = Vec::new();
    for behaviour in BEHAVIOURS {
        let name = Mover::file_name(&library, behaviour);
        let built = cache::encode(&Mover::build_parts(&library, behaviour, &mut |_| {}).unwrap());
        let shipped = cache::shipped(&name).map(|c| cache::encode(&c));
        if shipped.as_deref() == Some(built.as_slice()) {
            continue;
        }
        if write {
            replace(behaviour, &name, &built);
        } else {
            stale.push(match shipped {
                None => format!("{name}: not shipped"),
                Some(_) => format!("{name}: shipped, but not what the code builds"),
            });
        }
    }
    assert!(
        stale.is_empty(),
        "the shipped graphs and maps are stale ({}); run scripts/sync-capability and commit data/capability",
        stale.join("; ")
    );
}

/// Writes `bytes` as `data/capability/<name>.zst` and removes the behaviour's others.
fn replace(behaviour: &str, name: &str, bytes: &[u8]) {
    let dir = shipped_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let prefix = format!("capability-{behaviour}-");
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        if file.starts_with(&prefix) && file.ends_with(".bin.zst") {
            std::fs::remove_file(entry.path()).unwrap();
        }
    }
    let compressed = zstd::bulk::compress(bytes, 19).unwrap();
    std::fs::write(dir.join(format!("{name}.zst")), compressed).unwrap();
}

#[test]
fn every_shipped_file_is_a_behaviour_of_the_embedded_motion() {
    // Nothing is shipped that no lookup can find: each file is the current name of one
    // of the behaviours (a leftover of an older build would only grow the binary).
    let library = MotionLibrary::embedded(FPS, Mirroring::On);
    let current: Vec<String> = BEHAVIOURS
        .iter()
        .map(|b| Mover::file_name(&library, b))
        .collect();
    for name in cache::shipped_names() {
        assert!(
            current.iter().any(|c| c == name),
            "{name} is shipped but is not the file of any behaviour; run scripts/sync-capability"
        );
    }
}
