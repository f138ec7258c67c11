//! A replay file, any bytes (truncated, corrupted, hostile): read to what it holds or
//! refused with a reason, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(replay) = fieldhouse_core::replay::parse(data) {
        let _ = (replay.complete(), replay.match_id(), replay.frames_hash());
        let _: Vec<u64> = replay.log.iter().map(|l| l.tick()).collect();
    }
});
