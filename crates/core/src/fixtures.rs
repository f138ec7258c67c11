//! Small synthetic clips for tests: a stick figure on a known root path.

use crate::motion::*;
use glam::{DVec2, DVec3};
use std::f64::consts::TAU;

/// A stick figure whose root follows `path(t)` (ground position, heading) with a gait
/// phase driven by distance, sampled at 30 fps for `seconds`.
pub fn clip(name: &str, seconds: f64, path: impl Fn(f64) -> (DVec2, f64)) -> Clip {
    let names = ["Hips", LEFT_HIP, RIGHT_HIP, "LeftFoot", "RightFoot", "Head"];
    let frames = (seconds * FPS) as usize;
    let mut positions = Vec::new();
    let mut travelled = 0.0;
    let mut last = path(0.0).0;
    for f in 0..frames {
        let (root, heading) = path(f as f64 / FPS);
        travelled += (root - last).length();
        last = root;
        let phase = travelled / 2.4 * TAU;
        let fwd = DVec2::from_angle(heading);
        // With y up, a body facing +x has its left on −z.
        let left = DVec2::new(fwd.y, -fwd.x);
        let at = |forward: f64, side: f64, y: f64| {
            let g = root + fwd * forward + left * side;
            DVec3::new(g.x, y, g.y)
        };
        positions.extend([
            at(0.0, 0.0, 0.95 + 0.03 * (2.0 * phase).cos()),
            at(0.0, 0.1, 0.9),
            at(0.0, -0.1, 0.9),
            at(0.4 * phase.sin(), 0.1, 0.05),
            at(-0.4 * phase.sin(), -0.1, 0.05),
            at(0.0, 0.0, 1.7),
        ]);
    }
    Clip::new(
        name,
        "run",
        FPS,
        names.iter().map(|s| s.to_string()).collect(),
        positions,
    )
    .unwrap()
}

/// A path for [`clip`]: straight along +x at `speed` m/s, facing +x.
pub fn straight(speed: f64) -> impl Fn(f64) -> (DVec2, f64) {
    move |t| (DVec2::new(speed * t, 0.0), 0.0)
}

/// Circles toward +z (a right turn, +z being on the right of a body facing +x) for a
/// positive radius, toward −z for a negative one.
pub fn circle(speed: f64, radius: f64) -> impl Fn(f64) -> (DVec2, f64) {
    move |t| {
        let a = speed * t / radius;
        (DVec2::new(radius * a.sin(), radius * (1.0 - a.cos())), a)
    }
}

/// Jogging straight, circling left and right at 6 m and 2.5 m radius, and a faster stride.
pub fn library() -> Vec<Clip> {
    vec![
        clip("jog", 4.0, straight(3.5)),
        clip("right", 4.0, circle(3.5, 6.0)),
        clip("left", 4.0, circle(3.5, -6.0)),
        clip("stride", 4.0, straight(4.2)),
        clip("tight_right", 4.0, circle(3.5, 2.5)),
        clip("tight_left", 4.0, circle(3.5, -2.5)),
    ]
}

/// The motion graph of [`library`] with default parameters.
pub fn graph() -> MotionGraph {
    let clips = library();
    let refs: Vec<&Clip> = clips.iter().collect();
    MotionGraph::build("run", &refs, GraphParams::default()).unwrap()
}

/// The CMU motion capture embedded in the binary, loaded once per test binary.
pub fn cmu_library() -> &'static MotionLibrary {
    static LIBRARY: std::sync::OnceLock<MotionLibrary> = std::sync::OnceLock::new();
    LIBRARY.get_or_init(|| MotionLibrary::embedded(FPS, Mirroring::On))
}

/// The repository's copy of the motion capture, which the binary embeds: for tests of
/// the directory loader.
pub fn mocap_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/mocap")
}

/// The motion graph of a CMU behaviour, with the automatic threshold.
pub fn cmu_graph(behaviour: &str) -> MotionGraph {
    let library = cmu_library();
    let owned = library.ground_clips(behaviour);
    let clips: Vec<&Clip> = owned.iter().collect();
    MotionGraph::build_auto(behaviour, &clips, &AUTO_WINDOWS).unwrap()
}

/// The basketball behaviours of the CMU data, once per test binary: the graphs and maps
/// shipped in the binary (built, if the source changed since they were shipped, until
/// `scripts/sync-capability` is run; `shipped_capability` fails meanwhile).
pub fn cmu_capabilities() -> std::sync::Arc<crate::basketball::Capabilities> {
    static CAPS: std::sync::OnceLock<std::sync::Arc<crate::basketball::Capabilities>> =
        std::sync::OnceLock::new();
    CAPS.get_or_init(|| {
        std::sync::Arc::new(
            crate::basketball::Capabilities::build(
                cmu_library(),
                crate::costmap::cache::Reuse::Shipped,
                &mut |_| {},
            )
            .expect("the CMU behaviours build"),
        )
    })
    .clone()
}
