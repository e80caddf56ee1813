//! Operating the service: metrics, request ids, readiness, bearer-token authentication, and the
//! edge layer ([`edge`]) that applies them to every request of both transports. The domain crate
//! and the facade know nothing of this; the transports only name their routes and shape their
//! refusals ([`edge::EdgeHooks`]).

pub mod auth;
pub mod edge;
pub mod metrics;
pub mod readiness;

pub use auth::Tokens;
pub use metrics::Metrics;
pub use readiness::{Readiness, ReadyState};

use std::sync::Arc;

/// Which transport a request came through (a metrics label and a log field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transport {
    Grpc,
    Rest,
}

impl Transport {
    pub fn name(self) -> &'static str {
        match self {
            Transport::Grpc => "grpc",
            Transport::Rest => "rest",
        }
    }
}

/// What both transports share for operations; cheap to clone.
#[derive(Debug, Clone, Default)]
pub struct Ops {
    pub metrics: Metrics,
    pub readiness: Readiness,
    /// Empty: authentication is off.
    pub tokens: Arc<Tokens>,
}

impl Ops {
    pub fn new(tokens: Tokens) -> Self {
        Self {
            metrics: Metrics::new(),
            readiness: Readiness::new(),
            tokens: Arc::new(tokens),
        }
    }
}

/// The header (gRPC: metadata key) carrying the request id, both ways.
pub const REQUEST_ID_HEADER: &str = "x-request-id";

/// Longest caller-given request id kept; a longer one is replaced.
pub const MAX_REQUEST_ID_LEN: usize = 128;

/// The request's id, in the request's extensions for handlers that want it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RequestId(pub Arc<str>);

/// The caller's id if it is sane: 1 to [`MAX_REQUEST_ID_LEN`] visible ASCII characters.
pub fn sane_request_id(value: &[u8]) -> Option<&str> {
    if value.is_empty()
        || value.len() > MAX_REQUEST_ID_LEN
        || !value.iter().all(u8::is_ascii_graphic)
    {
        return None;
    }
    std::str::from_utf8(value).ok()
}

/// A fresh id: a random (version 4) UUID.
pub fn new_request_id() -> String {
    use rand::RngExt;
    let mut b: [u8; 16] = rand::rng().random();
    b[6] = (b[6] & 0x0f) | 0x40;
    b[8] = (b[8] & 0x3f) | 0x80;
    let h: String = b.iter().map(|x| format!("{x:02x}")).collect();
    format!(
        "{}-{}-{}-{}-{}",
        &h[0..8],
        &h[8..12],
        &h[12..16],
        &h[16..20],
        &h[20..32]
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_ids() {
        assert_eq!(sane_request_id(b"abc-123"), Some("abc-123"));
        assert_eq!(sane_request_id(&[b'a'; 128]).map(str::len), Some(128));
        assert_eq!(sane_request_id(&[b'a'; 129]), None);
        assert_eq!(sane_request_id(b""), None);
        assert_eq!(sane_request_id(b"has space"), None);
        assert_eq!(sane_request_id("é".as_bytes()), None);
        let a = new_request_id();
        assert_eq!(a.len(), 36);
        assert_eq!(&a[14..15], "4");
        assert!(sane_request_id(a.as_bytes()).is_some());
        assert_ne!(a, new_request_id());
    }
}
