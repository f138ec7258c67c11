//! PLACEHOLDER so the `synthetic` branch compiles: the real BVH loader is written on
//! another branch. Drop this file in favour of that one at merge.

pub(super) fn load_library(
    dir: &std::path::Path,
    _fps: f64,
) -> Result<super::MotionLibrary, super::LibraryError> {
    Err(super::LibraryError::Empty {
        dir: dir.to_path_buf(),
        problems: vec![],
    })
}
