//! The spectator page: plain HTML, CSS and JavaScript modules from `web/`, embedded in the
//! binary so the single file serves everywhere, with no build step between the sources
//! and what the browser runs.

use super::api::ApiError;
use axum::extract::Path;
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};

/// Every file of the page: its name under `/web/` and its media type. The page's modules
/// import each other by relative paths, so they all live side by side.
const ASSETS: &[(&str, &str, &str)] = &[
    (
        "index.html",
        "text/html; charset=utf-8",
        include_str!("../../../web/index.html"),
    ),
    (
        "style.css",
        "text/css; charset=utf-8",
        include_str!("../../../web/style.css"),
    ),
    ("app.js", JS, include_str!("../../../web/app.js")),
    ("lobby.js", JS, include_str!("../../../web/lobby.js")),
    ("view.js", JS, include_str!("../../../web/view.js")),
    ("stream.js", JS, include_str!("../../../web/stream.js")),
    ("timeline.js", JS, include_str!("../../../web/timeline.js")),
    ("draw.js", JS, include_str!("../../../web/draw.js")),
    ("fly.js", JS, include_str!("../../../web/fly.js")),
    ("eye.js", JS, include_str!("../../../web/eye.js")),
    ("court.js", JS, include_str!("../../../web/court.js")),
    ("player.js", JS, include_str!("../../../web/player.js")),
    ("labels.js", JS, include_str!("../../../web/labels.js")),
    ("view3d.js", JS, include_str!("../../../web/view3d.js")),
    ("pose.js", JS, include_str!("../../../web/pose.js")),
    (
        VENDORED_THREE,
        JS,
        include_str!("../../../web/vendor/three-0.170.0.module.min.js"),
    ),
];

/// three.js, vendored (web/vendor/README.md): its version is in its name, so a browser
/// may keep it for good; a new version is a new name.
const VENDORED_THREE: &str = "three-0.170.0.module.min.js";

const JS: &str = "text/javascript; charset=utf-8";

/// What a browser may do with any response of this server. The page is its own files
/// only: scripts and styles from `/web/` (no inline script or style, so a string the
/// page failed to escape cannot run), images from itself or drawn on canvases, sockets
/// and fetches to this server; it is framed by no one and submits no forms. A replay
/// header holding `<img onerror=...>` once ran script in the lobby: the policy stops
/// that class even if an escape is missed.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; script-src 'self'; \
    style-src 'self'; img-src 'self' data: blob:; connect-src 'self' ws: wss:; \
    object-src 'none'; base-uri 'none'; frame-ancestors 'none'; form-action 'none'";

/// Sets the security headers on every response: the [`CONTENT_SECURITY_POLICY`], no
/// MIME sniffing (a JSON body is never run as a script), and no referrer.
pub async fn security_headers(mut response: Response) -> Response {
    let headers = response.headers_mut();
    for (name, value) in [
        (header::CONTENT_SECURITY_POLICY, CONTENT_SECURITY_POLICY),
        (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        (header::REFERRER_POLICY, "no-referrer"),
    ] {
        headers.insert(name, HeaderValue::from_static(value));
    }
    response
}

/// `GET /`: the spectator page.
pub async fn index() -> Response {
    asset("index.html")
}

/// `GET /web/{file}`: a file beside the page (scripts, styles, vendored three.js).
pub async fn file(Path(name): Path<String>) -> Response {
    asset(&name)
}

fn asset(name: &str) -> Response {
    match ASSETS.iter().find(|(n, _, _)| *n == name) {
        // `no-cache`: the browser revalidates, so a new binary's page is never mixed
        // with an old one's modules (but for the versioned library).
        Some((file, media_type, body)) => (
            [
                (header::CONTENT_TYPE, *media_type),
                (
                    header::CACHE_CONTROL,
                    if *file == VENDORED_THREE {
                        "public, max-age=31536000, immutable"
                    } else {
                        "no-cache"
                    },
                ),
            ],
            *body,
        )
            .into_response(),
        None => ApiError::new(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no page file \"{name}\""),
        )
        .into_response(),
    }
}

#[cfg(test)]
mod tests {
    use super::ASSETS;

    /// A module written but not listed here is a page that fails to load in the
    /// browser (its import is a 404), with nothing said at build time.
    #[test]
    fn every_file_beside_the_page_is_served() {
        let web = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web");
        for entry in std::fs::read_dir(&web).unwrap() {
            let path = entry.unwrap().path();
            if !path.is_file() {
                continue;
            }
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let served = ASSETS.iter().find(|(file, _, _)| *file == name);
            let Some((_, _, body)) = served else {
                panic!("web/{name} is not embedded in ASSETS");
            };
            assert_eq!(*body, std::fs::read_to_string(&path).unwrap(), "{name}");
        }
    }
}
