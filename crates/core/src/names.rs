//! The names people type for presets (`--air nathan`, `--strategy lot-optical`), and the
//! one error every such name gives when it is wrong: what was asked for and what exists.

use thiserror::Error;

/// A name that matches no preset of its kind.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown {kind} \"{given}\"; expected one of {}", .expected.join(", "))]
pub struct UnknownName {
    kind: &'static str,
    given: String,
    expected: &'static [&'static str],
}

/// Looks `given` up among `choices`, each a name with its value.
pub fn lookup<T: Copy>(
    kind: &'static str,
    given: &str,
    names: &'static [&'static str],
    values: &[T],
) -> Result<T, UnknownName> {
    names
        .iter()
        .position(|n| *n == given)
        .map(|i| values[i])
        .ok_or_else(|| UnknownName {
            kind,
            given: given.to_string(),
            expected: names,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wrong_name_says_what_exists() {
        let err = lookup("colour", "mauve", &["red", "green"], &[1, 2]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown colour \"mauve\"; expected one of red, green"
        );
        assert_eq!(lookup("colour", "green", &["red", "green"], &[1, 2]), Ok(2));
    }
}
