//! `GET /api/motion/{behaviour}`: a behaviour's poses, sent once so frames can name a
//! node (and a blend) instead of carrying joint positions. The documents are built (and
//! gzipped) on first asking and kept, every response sharing their bytes; the browser
//! keeps them too, revalidating by ETag (`If-None-Match` as RFC 9110 reads it).

use super::api::ApiError;
use axum::body::Bytes;
use axum::extract::Path;
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use fieldhouse_core::basketball::Capabilities;
use fieldhouse_core::motion::PoseLibrary;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, OnceLock};

/// The behaviours served, as frames name them.
const BEHAVIOURS: [&str; 3] = ["dribble", "run", "defense"];

/// A served document: its JSON, the same gzipped (a megabyte of JSON is some 100 kB),
/// and its ETag. `Bytes` clone by reference count: no request copies a document.
struct Served {
    body: Bytes,
    gzip: Bytes,
    etag: HeaderValue,
}

/// Each behaviour's document, built once (up to a megabyte of JSON: worth building once,
/// not per spectator), from the capabilities the server's matches move with.
pub struct PoseDocuments {
    caps: Arc<Capabilities>,
    served: [OnceLock<Served>; 3],
}

impl PoseDocuments {
    /// The documents of `caps`' behaviours, each built when first asked for.
    pub fn new(caps: Arc<Capabilities>) -> PoseDocuments {
        PoseDocuments {
            caps,
            served: Default::default(),
        }
    }
}

/// `GET /api/motion/{behaviour}`: the behaviour's poses (gzipped if the client takes
/// it; 304 for a matching ETag).
pub async fn poses(
    Path(behaviour): Path<String>,
    docs: Arc<PoseDocuments>,
    request: HeaderMap,
) -> Result<Response, ApiError> {
    let (k, mover) = BEHAVIOURS
        .iter()
        .position(|b| *b == behaviour)
        .and_then(|k| Some((k, docs.caps.by_behaviour(&behaviour)?)))
        .ok_or_else(|| {
            ApiError::new(
                StatusCode::NOT_FOUND,
                "no_motion",
                format!(
                    "no motion for behaviour \"{behaviour}\" (there are {})",
                    BEHAVIOURS.join(", ")
                ),
            )
        })?;
    let served = docs.served[k].get_or_init(|| {
        let body = serde_json::to_string(&PoseLibrary::of(&mover.graph))
            .expect("pose libraries serialise");
        // The body's own hash: a server started with other capture serves other poses
        // under another tag.
        let mut hasher = std::hash::DefaultHasher::new();
        body.hash(&mut hasher);
        let etag = HeaderValue::from_str(&format!("\"{:016x}\"", hasher.finish()))
            .expect("hex is a header value");
        let mut gzip = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        std::io::Write::write_all(&mut gzip, body.as_bytes()).expect("writing to memory");
        let gzip = gzip.finish().expect("writing to memory");
        Served {
            body: Bytes::from(body),
            gzip: Bytes::from(gzip),
            etag,
        }
    });
    // `no-cache`: the browser keeps the document and asks each time whether it is still
    // the server's (a 304 costs nothing); a restart with other capture changes it.
    let cache = [
        (header::ETAG, served.etag.clone()),
        (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
        (header::VARY, HeaderValue::from_static("accept-encoding")),
    ];
    if none_match(&request, &served.etag) {
        return Ok((StatusCode::NOT_MODIFIED, cache).into_response());
    }
    let json = (
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    if accepts_gzip(&request) {
        let encoding = (header::CONTENT_ENCODING, HeaderValue::from_static("gzip"));
        return Ok((cache, [json, encoding], served.gzip.clone()).into_response());
    }
    Ok((cache, [json], served.body.clone()).into_response())
}

/// Whether `If-None-Match` names the document: `*`, or any tag of its lists equal to
/// `etag` by the weak comparison (a `W/` prefix ignored), as RFC 9110 (13.1.2) asks of a
/// GET.
fn none_match(request: &HeaderMap, etag: &HeaderValue) -> bool {
    let etag = etag.to_str().unwrap_or_default();
    request
        .get_all(header::IF_NONE_MATCH)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .any(|tag| tag == "*" || tag.strip_prefix("W/").unwrap_or(tag) == etag)
}

/// Whether `Accept-Encoding` takes gzip: `gzip` with a weight above 0, or, if gzip is
/// not named, `*` with one.
fn accepts_gzip(request: &HeaderMap) -> bool {
    let codings: Vec<(String, f64)> = request
        .get_all(header::ACCEPT_ENCODING)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .map(|coding| {
            let mut parts = coding.split(';').map(str::trim);
            let name = parts.next().unwrap_or_default().to_ascii_lowercase();
            let weight = parts
                .filter_map(|p| p.strip_prefix("q=").or_else(|| p.strip_prefix("Q=")))
                .find_map(|q| q.parse::<f64>().ok())
                .unwrap_or(1.0);
            (name, weight)
        })
        .collect();
    let weight_of = |name: &str| codings.iter().find(|(n, _)| n == name).map(|(_, w)| *w);
    weight_of("gzip")
        .or_else(|| weight_of("*"))
        .is_some_and(|w| w > 0.0)
}
