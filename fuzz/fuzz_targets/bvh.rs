//! A BVH motion-capture file, any bytes: a clip, or an error naming the line, never a
//! panic, and never a clip holding a non-finite position.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(clip) = fieldhouse_core::motion::parse_clip(data, "fuzz", "run", 30.0) {
        for f in 0..clip.frame_count() {
            assert!(clip.frame(f).iter().all(|p| p.is_finite()), "frame {f}");
        }
    }
});
