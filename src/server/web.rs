//! The spectator page, embedded in the binary so the server works anywhere.

use axum::response::{Html, IntoResponse};

pub async fn index() -> Html<&'static str> {
    Html(include_str!("../../web/index.html"))
}

pub async fn script() -> impl IntoResponse {
    (
        [("content-type", "text/javascript; charset=utf-8")],
        include_str!("../../web/app.js"),
    )
}
