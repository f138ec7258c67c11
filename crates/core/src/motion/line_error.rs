//! What every reader of a text format of motion reports: what is wrong, and the 1-based
//! line where it goes wrong, so a user can open the file there; and what any of them can
//! find wrong with a single token.

use thiserror::Error;

/// A file that cannot be read: `kind` says what is wrong (each format has its own kinds),
/// `line` where.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("line {line}: {kind}")]
pub(super) struct LineError<K: std::error::Error + 'static> {
    pub line: usize,
    pub kind: K,
}

/// What any text format can find wrong with a token; each format's own kinds wrap it.
#[derive(Debug, Clone, PartialEq, Error)]
pub(super) enum TokenError {
    #[error("the file ends where {expected} was expected")]
    UnexpectedEnd { expected: &'static str },
    #[error("expected {expected}, found `{found}`")]
    Unexpected {
        expected: &'static str,
        found: String,
    },
    #[error("`{text}` is not a number ({what})")]
    NotANumber { what: &'static str, text: String },
    #[error("`{text}` is not a finite number ({what})")]
    NonFinite { what: &'static str, text: String },
}

/// A token as an error message shows it: whole if short, else its start, so a hostile
/// file cannot make a message as long as itself.
pub(super) fn shown(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    match text.char_indices().nth(MAX_CHARS) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text.to_string(),
    }
}

/// A finite number, or an error at `line` naming `what` it was meant to be.
pub(super) fn number<K>(line: usize, text: &str, what: &'static str) -> Result<f64, LineError<K>>
where
    K: std::error::Error + From<TokenError> + 'static,
{
    let kind = match text.parse::<f64>() {
        Ok(v) if v.is_finite() => return Ok(v),
        Ok(_) => TokenError::NonFinite {
            what,
            text: shown(text),
        },
        Err(_) => TokenError::NotANumber {
            what,
            text: shown(text),
        },
    };
    Err(LineError {
        line,
        kind: kind.into(),
    })
}
