//! What every reader of a text format of motion reports: what is wrong, and the 1-based
//! line where it goes wrong, so a user can open the file there.

use thiserror::Error;

/// A file that cannot be read: `kind` says what is wrong (each format has its own kinds),
/// `line` where.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("line {line}: {kind}")]
pub(super) struct LineError<K: std::error::Error + 'static> {
    pub line: usize,
    pub kind: K,
}
