//! A replay file, any bytes (truncated, corrupted, hostile), read as the server reads
//! one for its viewers (the index reads positions of its bytes, here in memory): walked
//! into a block index, then played through, sought and sought back with a lead-in. Never
//! a panic, and reading stops (an error or the end).
#![no_main]

use fieldhouse_core::replay::{At, BlockCache, Index};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = data;
    let Ok(index) = Index::build(file) else {
        return;
    };
    let _ = (index.complete(), index.frames(), index.walked());
    let mut cache = BlockCache::default();
    let Ok((first, last)) = index.ends(file, &mut cache) else {
        return;
    };
    // Played through, a batch at a time: the place always moves on.
    let mut at = At::START;
    for _ in 0..10_000 {
        match index.read(file, &mut cache, at, 64, 64 * 1024) {
            Ok((frames, next)) if !frames.is_empty() => {
                assert!(next > at);
                at = next;
            }
            _ => break,
        }
    }
    for tick in [first.unwrap_or(0), last.unwrap_or(0), u64::MAX, 0] {
        if let Ok(Some(found)) = index.seek(file, &mut cache, tick) {
            let _ = index.back(file, &mut cache, found, At::START, 1000);
            let _ = index.read(file, &mut cache, found, 4, 1024);
        }
    }
});
