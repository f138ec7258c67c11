//! Tokens: 128 random bits from the operating system, written in hex, and compared in
//! constant time so a timing side channel does not leak them.

use rand::RngCore;

/// A fresh random token (128 bits, 32 hex digits).
pub fn new_token() -> String {
    let mut bytes = [0u8; 16];
    rand::rngs::OsRng.fill_bytes(&mut bytes);
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Whether `given` equals `expected`, taking the same time wherever they differ.
pub fn same(given: &str, expected: &str) -> bool {
    let (a, b) = (given.as_bytes(), expected.as_bytes());
    let mut diff = (a.len() ^ b.len()) as u8 | u8::from(a.len() != b.len());
    for (k, &y) in b.iter().enumerate() {
        diff |= a.get(k).copied().unwrap_or(0) ^ y;
    }
    diff == 0
}

/// The bearer token of an `Authorization` header value, if it is one. The scheme is
/// matched without regard to case (RFC 7235: `BEARER t` is `Bearer t`), and any run of
/// spaces or tabs may separate it from the token.
pub fn bearer(header: &str) -> Option<&str> {
    let (scheme, token) = header.trim().split_once([' ', '\t'])?;
    let token = token.trim();
    (scheme.eq_ignore_ascii_case("bearer") && !token.is_empty()).then_some(token)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_random_and_compare_exactly() {
        let (a, b) = (new_token(), new_token());
        assert_eq!(a.len(), 32);
        assert_ne!(a, b);
        assert!(same(&a, &a.clone()));
        assert!(!same(&a, &b));
        assert!(!same(&a[..31], &a));
        assert!(!same(&format!("{a}0"), &a));
        assert!(!same("", &a));
        assert_eq!(bearer("Bearer abc"), Some("abc"));
        assert_eq!(bearer("Basic abc"), None);
    }

    #[test]
    fn the_bearer_scheme_is_read_in_any_case_with_any_spacing() {
        for header in [
            "Bearer abc",
            "bearer abc",
            "BEARER abc",
            "bEaReR abc",
            "Bearer    abc",
            "Bearer\tabc ",
            " Bearer abc",
        ] {
            assert_eq!(bearer(header), Some("abc"), "{header:?}");
        }
        for header in [
            "Bearer",
            "Bearer ",
            "Bearerabc",
            "Basic abc",
            "Bearers abc",
            "",
        ] {
            assert_eq!(bearer(header), None, "{header:?}");
        }
    }
}
