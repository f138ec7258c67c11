//! Tokens: 128 random bits from the operating system, written in hex, and compared in
//! constant time so a timing side channel does not leak them.

use rand::RngCore;
use subtle::ConstantTimeEq;

/// A fresh random token (128 bits, 32 hex digits).
pub fn new_token() -> String {
    let mut bytes = [0u8; 16];
    rand::rngs::OsRng.fill_bytes(&mut bytes);
    hex::encode(bytes)
}

/// Whether `given` equals `expected`, taking the same time wherever they differ (`subtle`:
/// only a wrong length, which is no secret, answers early).
pub fn same(given: &str, expected: &str) -> bool {
    bool::from(given.as_bytes().ct_eq(expected.as_bytes()))
}

/// The admin token, and where this server got it: a wrong token's refusal says how to
/// find the right one, which differs between a token the operator chose and one the
/// server made up and printed once. Its `Debug` never shows the secret.
#[derive(Clone)]
pub struct AdminToken {
    secret: String,
    chosen: bool,
}

impl AdminToken {
    /// A token the operator chose (`FIELDHOUSE_ADMIN_TOKEN`).
    pub fn chosen(secret: String) -> AdminToken {
        AdminToken {
            secret,
            chosen: true,
        }
    }

    /// A token the server made at start ([`new_token`]) and printed on its terminal.
    pub fn generated(secret: String) -> AdminToken {
        AdminToken {
            secret,
            chosen: false,
        }
    }

    /// Whether `given` is this token (in constant time).
    pub fn is(&self, given: &str) -> bool {
        same(given, &self.secret)
    }

    /// What a 403 says: the token is wrong, and where this server's comes from.
    pub fn refusal(&self) -> &'static str {
        if self.chosen {
            "wrong admin token: this server's is the FIELDHOUSE_ADMIN_TOKEN it was started with"
        } else {
            "wrong admin token: this server was started without FIELDHOUSE_ADMIN_TOKEN, so it \
             made one and printed it once on its standard error (\"admin token (set \
             FIELDHOUSE_ADMIN_TOKEN to choose one): …\"); use that one, or restart it with \
             FIELDHOUSE_ADMIN_TOKEN set to the token you send"
        }
    }
}

impl std::fmt::Debug for AdminToken {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AdminToken")
            .field("chosen", &self.chosen)
            .finish_non_exhaustive()
    }
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
    fn a_refusal_says_where_the_servers_token_came_from_and_never_shows_it() {
        let secret = new_token();
        let chosen = AdminToken::chosen(secret.clone());
        let made = AdminToken::generated(secret.clone());
        assert!(chosen.is(&secret) && made.is(&secret) && !made.is("other"));
        assert!(chosen
            .refusal()
            .contains("the FIELDHOUSE_ADMIN_TOKEN it was started with"));
        // A server that made its own says where it printed it and how to choose one.
        assert!(made
            .refusal()
            .contains("printed it once on its standard error"));
        assert!(made
            .refusal()
            .contains("restart it with FIELDHOUSE_ADMIN_TOKEN set"));
        for token in [&chosen, &made] {
            assert!(!token.refusal().contains(&secret));
            assert!(!format!("{token:?}").contains(&secret));
        }
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
