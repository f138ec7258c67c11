//! CMU's ASF/AMC motion capture, any bytes: the skeleton, a NUL byte, then the motion
//! (without a NUL the whole input is the skeleton, read on its own). A clip, or an
//! error naming the line, never a panic, and never a clip holding a non-finite position.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let (asf, amc) = match data.iter().position(|&b| b == 0) {
        Some(nul) => (&data[..nul], &data[nul + 1..]),
        None => (data, &[][..]),
    };
    if let Ok(clip) = fieldhouse_core::motion::parse_acclaim_clip(asf, amc, "fuzz", "defense", 30.0)
    {
        for f in 0..clip.frame_count() {
            assert!(clip.frame(f).iter().all(|p| p.is_finite()), "frame {f}");
        }
    }
});
