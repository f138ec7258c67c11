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

/// `name` as a string that lives as long as the program: one copy per distinct name,
/// kept for good. For the handful of behaviour names a motion library has (folder names,
/// such as `run-127`), which label players in every frame, as the built-in ones do.
pub fn intern(name: &str) -> &'static str {
    static NAMES: std::sync::Mutex<std::collections::BTreeSet<&'static str>> =
        std::sync::Mutex::new(std::collections::BTreeSet::new());
    let mut names = NAMES
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some(&known) = names.get(name) {
        return known;
    }
    let leaked: &'static str = Box::leak(name.to_owned().into_boxed_str());
    names.insert(leaked);
    leaked
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

    #[test]
    fn a_name_is_interned_once() {
        let a = intern("run-127");
        let b = intern(&String::from("run-127"));
        assert_eq!(a, "run-127");
        assert!(std::ptr::eq(a, b));
    }
}
