//! The repository's motion capture is byte for byte what its manifest lists: every
//! `data/mocap/<behaviour>/*.bvh`, and every ASF skeleton and AMC motion in CMU's native
//! format beside them, has the checksum `data/mocap/SHA256SUMS` gives it, no file is
//! missing or unlisted, and the README's table (which carries the attribution CMU
//! asks for) names every file with the same checksum. `scripts/sync-mocap` writes both;
//! this catches a file edited, converted (line endings) or added by hand.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/mocap")
}

/// The kinds of file the loader reads, so the kinds the manifest must cover.
const KINDS: [&str; 3] = [".bvh", ".asf", ".amc"];

/// `behaviour/file.bvh` → sha256 hex, as listed in SHA256SUMS.
fn manifest() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(data().join("SHA256SUMS")).expect("SHA256SUMS is there");
    text.lines()
        .map(|line| {
            let (sum, path) = line
                .split_once("  ")
                .unwrap_or_else(|| panic!("not a sha256sum line: {line:?}"));
            (path.to_string(), sum.to_string())
        })
        .collect()
}

/// `behaviour/file.bvh` → sha256 hex of the file as it is in the working tree.
fn files() -> BTreeMap<String, String> {
    let mut found = BTreeMap::new();
    for behaviour in std::fs::read_dir(data()).unwrap().flatten() {
        if !behaviour.path().is_dir() {
            continue;
        }
        for file in std::fs::read_dir(behaviour.path()).unwrap().flatten() {
            let name = file.file_name().to_string_lossy().into_owned();
            let lower = name.to_ascii_lowercase();
            if !KINDS.iter().any(|kind| lower.ends_with(kind)) {
                continue;
            }
            let bytes = std::fs::read(file.path()).unwrap();
            let sum = hex::encode(Sha256::digest(&bytes));
            found.insert(
                format!("{}/{name}", behaviour.file_name().to_string_lossy()),
                sum,
            );
        }
    }
    found
}

#[test]
fn every_file_matches_its_listed_checksum_and_nothing_is_unlisted() {
    let listed = manifest();
    let present = files();
    assert!(
        listed.len() >= 24,
        "the manifest lists {} files",
        listed.len()
    );
    for (path, sum) in &listed {
        match present.get(path) {
            None => panic!("{path} is listed in SHA256SUMS but missing"),
            Some(actual) => assert_eq!(
                actual, sum,
                "{path} differs from its listed checksum (edited, or line endings converted?)"
            ),
        }
    }
    for path in present.keys() {
        assert!(
            listed.contains_key(path),
            "{path} is not listed: run scripts/sync-mocap"
        );
    }
}

#[test]
fn the_readme_lists_every_file_with_its_checksum_and_the_attribution() {
    let readme = std::fs::read_to_string(data().join("README.md")).unwrap();
    for (path, sum) in manifest() {
        let row = readme
            .lines()
            .find(|l| l.starts_with(&format!("| `{path}` |")))
            .unwrap_or_else(|| panic!("the README's table has no row for {path}"));
        assert!(row.contains(&sum), "the README's row for {path}: {row}");
    }
    for must in [
        "mocap.cs.cmu.edu",
        "The database was created with funding from NSF EIA-0196217.",
        "you may not resell",
    ] {
        assert!(readme.contains(must), "the README does not say {must:?}");
    }
}

#[test]
fn the_readme_counts_the_frames_of_every_amc_file() {
    // An AMC file numbers its frames (1, 2, ...) and states no rate: CMU captures at
    // 120 Hz. A skeleton has no frames.
    let readme = std::fs::read_to_string(data().join("README.md")).unwrap();
    let mut amc_files = 0;
    for path in manifest().keys() {
        let row = readme
            .lines()
            .find(|l| l.starts_with(&format!("| `{path}` |")))
            .unwrap();
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let (frames, seconds) = (cells[5], cells[6]);
        if path.ends_with(".asf") {
            assert_eq!((frames, seconds), ("–", "–"), "{path}");
        } else if path.ends_with(".amc") {
            amc_files += 1;
            let text = std::fs::read_to_string(data().join(path)).unwrap();
            let numbers: Vec<usize> = text.lines().filter_map(|l| l.trim().parse().ok()).collect();
            assert_eq!(numbers, (1..=numbers.len()).collect::<Vec<_>>(), "{path}");
            assert_eq!(frames, numbers.len().to_string(), "{path}");
            assert_eq!(
                seconds,
                format!("{:.2}", numbers.len() as f64 / 120.0),
                "{path}"
            );
        }
    }
    assert!(amc_files >= 3, "{amc_files} AMC files");
}
