//! Human motion: clips of motion capture (BVH) or a synthetic stand-in, and the motion
//! graphs built from them.

mod alignment;
mod clip;
mod graph;
mod transitions;

pub use alignment::{GroundTransform, Moments};
pub use clip::{Clip, ClipError, LEFT_HIP, RIGHT_HIP};
pub use graph::{
    wrap_angle, Constraints, Edge, GraphError, GraphParams, GraphStats, MotionGraph, Node, RootStep,
};
pub use transitions::Transition;

/// The frame rate everything downstream works at: the paper plays motion at 30 fps.
pub const FPS: f64 = 30.0;
#[cfg(test)]
pub(crate) mod fixtures;
#[cfg(test)]
mod graph_tests;
