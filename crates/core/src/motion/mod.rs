//! Human motion: clips of motion capture (BVH, or CMU's native ASF/AMC), and the motion
//! graphs built from them.
//!
//! BVH files go through `bvh` (parse) and `skeleton` (forward kinematics to metres); CMU's
//! native files through `asf` (the skeleton), `amc` (the motion read against it) and
//! `acclaim` (forward kinematics to the joints Hahne's BVH conversion has, so clips of
//! both formats compare frame by frame). Both then go through `resample` (to [`FPS`]) and
//! `loader` (behaviour folders of files) into a [`MotionLibrary`] of [`Clip`]s, each also
//! played mirrored (`mirror`); `embedded` holds the CMU capture compiled into the binary,
//! the default everywhere. `jump` finds where a clip rises into a jump shot, which ends
//! the part of a clip the ground-locomotion graphs use.
//! `transitions` finds where clips can cut into each other (`alignment` is the ground
//! alignment it uses), `graph` turns clips and transitions into a [`MotionGraph`], and
//! `playback` plays a walk on it as a body, blending across transitions; `poses` is a
//! graph's poses and running loops as a spectator draws them; `turn` is how soon a body
//! can turn around on the spot, which a cost map (positions only) cannot say.

mod acclaim;
mod alignment;
mod amc;
mod asf;
mod bvh;
mod clip;
mod cuts;
mod embedded;
mod graph;
mod jump;
mod library;
mod line_error;
mod loader;
mod mirror;
mod playback;
mod poses;
mod resample;
mod skeleton;
mod step;
mod transitions;
mod turn;
mod walker;

pub use clip::Clip;
pub(crate) use clip::ClipError;
// The hip joints' names, for the synthetic clips of the fixtures.
#[cfg(any(test, feature = "fixtures"))]
pub(crate) use clip::{LEFT_HIP, RIGHT_HIP};
pub use graph::{
    ClipCoverage, Constraints, Edge, GraphError, GraphParams, GraphStats, MotionGraph,
    AUTO_THRESHOLDS_M, AUTO_WINDOWS,
};
pub use jump::Jump;
pub use library::{LibraryError, LoadProblem, Mirroring, MotionLibrary, MotionSource};
pub use loader::{parse_acclaim_clip, parse_clip};
pub use playback::{Blend, PlaybackFrame};
pub use poses::{PoseLibrary, StrideCycle, MAX_FOOT_SLIDE_M};
pub use step::{wrap_angle, Node, RootStep};
pub use turn::{quickest_turn_around, turn_around, TurnAround, TurnParams};
pub use walker::Walker;

/// The frame rate everything downstream works at: the paper plays motion at 30 fps.
pub const FPS: f64 = 30.0;

#[cfg(test)]
mod graph_tests;
