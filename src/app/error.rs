//! What a use case can refuse, and why, in words a person can act on. The web maps each kind
//! to a status code (`web::error`); the command line prints the message and exits non-zero.
//! Everything unexpected is `Internal`: its details go to the log, never to the client.

use crate::core::submission::LineProblem;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error("{0}")]
    NotFound(String),
    #[error("{0}")]
    BadRequest(String),
    /// No valid bearer token (missing, unknown or revoked), or no login session.
    #[error("{0}")]
    Unauthorized(String),
    /// A token without the scope the request needs, or a page or item that is not this
    /// annotator's (or a wrong CSRF token).
    #[error("{0}")]
    Forbidden(String),
    #[error("{0}")]
    Conflict(String),
    #[error("{0}")]
    PayloadTooLarge(String),
    /// A body in a format the route does not take.
    #[error("{0}")]
    UnsupportedMediaType(String),
    /// The body was read but refused; `problems` says where.
    #[error("{message}")]
    Unprocessable {
        message: String,
        problems: Vec<LineProblem>,
    },
    /// A quota or rate limit. `retry_after` is set only when waiting helps: a used-up total
    /// quota never refills, so it sends no `Retry-After`.
    #[error("{message}")]
    TooManyRequests {
        message: String,
        retry_after: Option<u64>,
    },
    /// Something the server depends on (frame storage) failed or is not configured; the
    /// message names it.
    #[error("{0}")]
    Unavailable(String),
    #[error("internal error")]
    Internal(#[source] anyhow::Error),
}

impl AppError {
    /// An unexpected failure with context for the log.
    pub fn internal(context: impl std::fmt::Display) -> AppError {
        AppError::Internal(anyhow::anyhow!("{context}"))
    }
}

impl From<sqlx::Error> for AppError {
    fn from(e: sqlx::Error) -> Self {
        // PostgreSQL refuses text holding a NUL character (SQLite stores it): that is the
        // input's fault, not the server's.
        if let sqlx::Error::Database(db) = &e
            && db.code().as_deref() == Some("22021")
        {
            return AppError::BadRequest(
                "text with a NUL character (\\u0000) cannot be stored or looked up".into(),
            );
        }
        AppError::Internal(e.into())
    }
}

impl From<tokio::task::JoinError> for AppError {
    fn from(e: tokio::task::JoinError) -> Self {
        AppError::Internal(e.into())
    }
}

impl From<serde_json::Error> for AppError {
    fn from(e: serde_json::Error) -> Self {
        AppError::Internal(e.into())
    }
}

impl From<std::io::Error> for AppError {
    fn from(e: std::io::Error) -> Self {
        AppError::Internal(e.into())
    }
}

impl From<anyhow::Error> for AppError {
    fn from(e: anyhow::Error) -> Self {
        AppError::Internal(e)
    }
}
