//! The error every HTTP endpoint answers with: JSON `{"error": {"code": .., "message":
//! ..}}` and the status that fits. A leaf: the API, admission and replay endpoints all
//! use it, and it uses none of them.

use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde_json::json;

/// An HTTP error answer: its status, a stable machine-readable `code` and a message for
/// people.
#[derive(Debug)]
pub struct ApiError {
    status: StatusCode,
    code: &'static str,
    message: String,
}

impl ApiError {
    /// An error of `status` with its `code` and `message`.
    pub fn new(status: StatusCode, code: &'static str, message: impl Into<String>) -> Self {
        ApiError {
            status,
            code,
            message: message.into(),
        }
    }
    /// 404 `not_found`: no match `id`.
    pub fn not_found(id: &str) -> Self {
        Self::new(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no match \"{id}\""),
        )
    }
    /// 410 `ended`: match `id` has ended.
    pub fn gone(id: &str) -> Self {
        Self::new(
            StatusCode::GONE,
            "ended",
            format!("match \"{id}\" has ended"),
        )
    }
    /// 401 `unauthorized`: the request needs a token it did not bring.
    pub fn unauthorized(message: &str) -> Self {
        Self::new(StatusCode::UNAUTHORIZED, "unauthorized", message)
    }
    /// 403 `forbidden`: the caller is known but may not do this (a wrong token, an origin
    /// not allowed).
    pub fn forbidden(message: &str) -> Self {
        Self::new(StatusCode::FORBIDDEN, "forbidden", message)
    }
    /// A query parameter the route does not take, or a value it cannot.
    pub fn bad_query(message: impl Into<String>) -> Self {
        Self::new(StatusCode::BAD_REQUEST, "bad_query", message)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = json!({"error": {"code": self.code, "message": self.message}});
        (self.status, Json(body)).into_response()
    }
}
