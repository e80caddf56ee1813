//! Optional bearer-token authentication: `authorization: Bearer <token>` on REST requests and as
//! gRPC metadata, compared in constant time against every configured token. Only SHA-256 digests
//! of the tokens are kept and compared, so neither the comparison's time nor memory tells a
//! token's content or length.
//!
//! Tokens never reach logs: [`Tokens`]' `Debug` prints only their count, and the configuration
//! prints a count instead of them.

use ring::digest::{SHA256, digest};
use subtle::{Choice, ConstantTimeEq};

/// The configured tokens (their SHA-256 digests); empty means authentication is off.
#[derive(Clone, Default, PartialEq, Eq)]
pub struct Tokens(Vec<[u8; 32]>);

fn sha256(bytes: &[u8]) -> [u8; 32] {
    let mut out = [0; 32];
    out.copy_from_slice(digest(&SHA256, bytes).as_ref());
    out
}

impl std::fmt::Debug for Tokens {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Tokens({} configured)", self.0.len())
    }
}

/// Longest token accepted in the configuration.
pub const MAX_TOKEN_LEN: usize = 4096;

impl Tokens {
    /// Checks each token (non-empty, at most [`MAX_TOKEN_LEN`] visible ASCII characters: what an
    /// `authorization` header can carry) and drops duplicates. `source` names where they came
    /// from in the error, which never quotes the token.
    pub fn new<S: AsRef<str>>(
        tokens: impl IntoIterator<Item = S>,
        source: &str,
    ) -> Result<Self, String> {
        let mut out: Vec<[u8; 32]> = Vec::new();
        for (i, token) in tokens.into_iter().enumerate() {
            let token = token.as_ref();
            if token.is_empty() || token.len() > MAX_TOKEN_LEN {
                return Err(format!(
                    "{source}: token {} is empty or longer than {MAX_TOKEN_LEN} characters",
                    i + 1
                ));
            }
            if !token.bytes().all(|b| b.is_ascii_graphic()) {
                return Err(format!(
                    "{source}: token {} has a character that is not visible ASCII (spaces and control characters cannot be sent in a header)",
                    i + 1
                ));
            }
            let token = sha256(token.as_bytes());
            if !out.contains(&token) {
                out.push(token);
            }
        }
        Ok(Self(out))
    }

    /// Reads a tokens file: one token per line; blank lines and lines starting with `#` are
    /// skipped, surrounding whitespace is trimmed.
    pub fn parse_file(text: &str, source: &str) -> Result<Self, String> {
        Self::new(
            text.lines()
                .map(str::trim)
                .filter(|l| !l.is_empty() && !l.starts_with('#')),
            source,
        )
    }

    pub fn merge(mut self, other: Tokens) -> Self {
        for t in other.0 {
            if !self.0.contains(&t) {
                self.0.push(t);
            }
        }
        self
    }

    pub fn len(&self) -> usize {
        self.0.len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether `authorization` (the header's value, if any) carries one of the tokens. The
    /// presented token's digest is compared with every token's, each in constant time, so the
    /// time does not tell which token matched, how much of one did, or how long they are.
    pub fn accepts(&self, authorization: Option<&[u8]>) -> bool {
        let Some(presented) = authorization.and_then(bearer) else {
            return false;
        };
        let presented = sha256(presented);
        let mut matched = Choice::from(0);
        for token in &self.0 {
            matched |= token.ct_eq(&presented);
        }
        bool::from(matched)
    }
}

/// The token of `Bearer <token>` (scheme case-insensitive, RFC 6750).
fn bearer(value: &[u8]) -> Option<&[u8]> {
    let (scheme, rest) = value.split_at_checked(6)?;
    if !scheme.eq_ignore_ascii_case(b"bearer") || rest.first() != Some(&b' ') {
        return None;
    }
    let token = rest.trim_ascii();
    (!token.is_empty()).then_some(token)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_only_configured_bearer_tokens() {
        let t = Tokens::new(["s3cret-one", "two"], "test").unwrap();
        assert!(t.accepts(Some(b"Bearer s3cret-one")));
        assert!(t.accepts(Some(b"bearer two")));
        assert!(t.accepts(Some(b"BEARER   two ")));
        assert!(!t.accepts(Some(b"Bearer s3cret-on")));
        assert!(!t.accepts(Some(b"Bearer s3cret-one2")));
        assert!(!t.accepts(Some(b"Basic two")));
        assert!(!t.accepts(Some(b"Bearertwo")));
        assert!(!t.accepts(Some(b"Bearer ")));
        assert!(!t.accepts(None));
        assert!(!Tokens::default().accepts(Some(b"Bearer two")));
    }

    #[test]
    fn checks_tokens_and_never_shows_them() {
        assert!(Tokens::new([""], "x").is_err());
        let e = Tokens::new(["has space"], "--auth-token").unwrap_err();
        assert!(e.contains("token 1") && !e.contains("has space"), "{e}");
        let t = Tokens::parse_file("# tokens\n  abc  \n\nabc\ndef\n", "file").unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(format!("{t:?}"), "Tokens(2 configured)");
        let merged = t.merge(Tokens::new(["def", "ghi"], "x").unwrap());
        assert_eq!(merged.len(), 3);
    }
}
