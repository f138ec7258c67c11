//! `GET /api/motion/{behaviour}`: a behaviour's poses, sent once so frames can name a
//! node (and a blend) instead of carrying joint positions. The documents are built on
//! first asking and kept; the browser keeps them too, revalidating by ETag.

use super::api::ApiError;
use axum::extract::Path;
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use fieldhouse_core::basketball::Capabilities;
use fieldhouse_core::motion::PoseLibrary;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, OnceLock};

/// The behaviours served, as frames name them.
const BEHAVIOURS: [&str; 3] = ["dribble", "run", "defense"];

/// A served document: its JSON and its ETag.
struct Served {
    body: String,
    etag: HeaderValue,
}

/// Each behaviour's document, built once (up to a megabyte of JSON: worth building once,
/// not per spectator), from the capabilities the server's matches move with.
pub struct PoseDocuments {
    caps: Arc<Capabilities>,
    served: [OnceLock<Served>; 3],
}

impl PoseDocuments {
    pub fn new(caps: Arc<Capabilities>) -> PoseDocuments {
        PoseDocuments {
            caps,
            served: Default::default(),
        }
    }
}

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
        Served { body, etag }
    });
    // `no-cache`: the browser keeps the document and asks each time whether it is still
    // the server's (a 304 costs nothing); a restart with other capture changes it.
    let cache = [
        (header::ETAG, served.etag.clone()),
        (header::CACHE_CONTROL, HeaderValue::from_static("no-cache")),
    ];
    if request
        .get_all(header::IF_NONE_MATCH)
        .iter()
        .any(|tag| tag == served.etag)
    {
        return Ok((StatusCode::NOT_MODIFIED, cache).into_response());
    }
    Ok((
        cache,
        [(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/json"),
        )],
        served.body.clone(),
    )
        .into_response())
}
