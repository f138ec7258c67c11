//! Placeholder for the synthetic locomotion library, which is written on another
//! branch; this empty stand-in only lets the BVH branch build and is dropped at merge.

pub(super) fn clips(_fps: f64) -> Vec<super::Clip> {
    Vec::new()
}
