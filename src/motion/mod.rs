//! Human motion: clips of motion capture (BVH) or a synthetic stand-in, and the motion
//! graphs built from them.

mod bvh;
mod clip;
mod library;
mod synthetic;

pub use clip::{Clip, ClipError, LEFT_HIP, RIGHT_HIP};
pub use library::{LibraryError, LoadProblem, MotionLibrary, MotionSource};

/// The frame rate everything downstream works at: the paper plays motion at 30 fps.
pub const FPS: f64 = 30.0;
