//! Changing a clip's frame rate: capture runs at 120 Hz, everything downstream at the
//! rate the motion graph plays (30 fps).

use glam::DVec3;

/// Resamples frame-major joint positions from `source_rate` to `fps` frames per second,
/// sampling at t = k/fps from the first frame to the last.
///
/// Global joint *positions* are interpolated linearly, not joint rotations: at an
/// integer ratio of rates (120 → 30 takes every 4th frame) every sample lands on a
/// source frame and the result is exact; in between, bones may shorten by a hair, which
/// at 120 Hz is far below capture noise. Positions are what a clip stores anyway.
pub(super) fn resample(
    positions: &[DVec3],
    joints: usize,
    source_rate: f64,
    fps: f64,
) -> Vec<DVec3> {
    let frames = positions.len() / joints;
    if frames == 0 {
        return Vec::new();
    }
    let span_s = (frames - 1) as f64 / source_rate;
    // The tolerance keeps a last sample that lands on the last frame up to rounding.
    let samples = (span_s * fps + 1e-9).floor() as usize + 1;
    let frame = |i: usize| &positions[i * joints..(i + 1) * joints];
    let mut out = Vec::with_capacity(samples * joints);
    for k in 0..samples {
        let u = k as f64 * source_rate / fps;
        let i = (u.floor() as usize).min(frames - 1);
        let w = u - i as f64;
        if i + 1 == frames || w < 1e-9 {
            out.extend_from_slice(frame(i));
        } else {
            let (a, b) = (frame(i), frame(i + 1));
            out.extend(a.iter().zip(b).map(|(a, b)| a.lerp(*b, w)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two joints, one moving along x at 1 unit per source frame.
    fn ramp(frames: usize) -> Vec<DVec3> {
        (0..frames)
            .flat_map(|f| [DVec3::new(f as f64, 0.0, 0.0), DVec3::Y])
            .collect()
    }

    #[test]
    fn integer_ratio_takes_every_nth_frame() {
        // 189 captured frames at 120 Hz span 188/120 s: samples at 0, 4, ..., 188.
        let out = resample(&ramp(189), 2, 120.0, 30.0);
        assert_eq!(out.len(), 48 * 2);
        for (k, pair) in out.chunks(2).enumerate() {
            assert_eq!(pair, [DVec3::new(4.0 * k as f64, 0.0, 0.0), DVec3::Y]);
        }
        // One frame fewer and the last sample no longer fits.
        assert_eq!(resample(&ramp(188), 2, 120.0, 30.0).len(), 47 * 2);
    }

    #[test]
    fn other_ratios_interpolate_between_frames() {
        // 100 Hz to 30 fps: sample 1 falls a third of the way from frame 3 to frame 4.
        let out = resample(&ramp(11), 2, 100.0, 30.0);
        assert_eq!(out.len(), 4 * 2);
        assert!((out[2].x - 10.0 / 3.0).abs() < 1e-12);
        assert!((out[6].x - 10.0).abs() < 1e-9);
    }

    #[test]
    fn upsampling_and_single_frames_work() {
        let out = resample(&ramp(3), 2, 30.0, 60.0);
        let xs: Vec<f64> = out.chunks(2).map(|p| p[0].x).collect();
        assert_eq!(xs, [0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(resample(&ramp(1), 2, 120.0, 30.0), ramp(1));
    }
}
