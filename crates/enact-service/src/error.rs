//! What a use case can refuse, and why, in words a person can act on. The variants say what
//! went wrong in the application's terms; the web maps each to a status code in one place
//! (`web::error`), the command line prints the message and exits non-zero. Everything
//! unexpected is `Internal`: its details go to the log, never to the client.

use super::refusal::{Refusal, RefusalKind};
use crate::core::submission::LineProblem;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// A refusal whose reason is typed ([`Refusal`]): each edge words it in its own way.
    #[error("{0}")]
    Refused(Refusal),
    /// What was asked for does not exist (or is not this caller's to see).
    #[error("{0}")]
    NotFound(String),
    /// The request's input is malformed or out of range: a field, a parameter, a name.
    #[error("{0}")]
    Invalid(String),
    /// No valid bearer token (missing, unknown or revoked), or no login session.
    #[error("{0}")]
    Unauthenticated(String),
    /// The caller is known but may not do this: a token without the scope the request needs,
    /// a page or item that is not this annotator's, or a wrong CSRF token.
    #[error("{0}")]
    NotPermitted(String),
    /// The request contradicts what is stored: a name in use, a finished item, a protocol
    /// that already ran, an idempotency key used with another body.
    #[error("{0}")]
    Conflict(String),
    /// The input is larger than the limit for it.
    #[error("{0}")]
    TooLarge(String),
    /// The input is in a format this use case does not take.
    #[error("{0}")]
    UnsupportedFormat(String),
    /// The input was read but refused as a whole; `problems` says where.
    #[error("{message}")]
    Rejected {
        message: String,
        problems: Vec<LineProblem>,
    },
    /// A quota or rate limit is used up. `retry_after` (seconds) is set only when waiting
    /// helps: a used-up total quota never refills.
    #[error("{message}")]
    LimitReached {
        message: String,
        retry_after: Option<u64>,
    },
    /// Something the server depends on (frame storage, or the database when a write cannot
    /// get its lock in time) failed or is not configured; the message names it. Worth
    /// retrying after a moment.
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

    /// Whether what was asked for does not exist, typed or not.
    pub fn is_not_found(&self) -> bool {
        match self {
            AppError::NotFound(_) => true,
            AppError::Refused(r) => r.kind() == RefusalKind::NotFound,
            _ => false,
        }
    }

    /// The codes of the kinds, which a refusal not yet typed is answered with.
    pub const KIND_CODES: [&'static str; 11] = [
        "not_found",
        "invalid",
        "unauthenticated",
        "not_permitted",
        "conflict",
        "too_large",
        "unsupported_format",
        "rejected",
        "limit_reached",
        "unavailable",
        "internal",
    ];

    /// The stable code the API answers with: the refusal's own for a typed refusal, else the
    /// kind's.
    pub fn code(&self) -> &'static str {
        match self {
            AppError::Refused(r) => r.code(),
            AppError::NotFound(_) => "not_found",
            AppError::Invalid(_) => "invalid",
            AppError::Unauthenticated(_) => "unauthenticated",
            AppError::NotPermitted(_) => "not_permitted",
            AppError::Conflict(_) => "conflict",
            AppError::TooLarge(_) => "too_large",
            AppError::UnsupportedFormat(_) => "unsupported_format",
            AppError::Rejected { .. } => "rejected",
            AppError::LimitReached { .. } => "limit_reached",
            AppError::Unavailable(_) => "unavailable",
            AppError::Internal(_) => "internal",
        }
    }
}

impl From<Refusal> for AppError {
    fn from(r: Refusal) -> Self {
        AppError::Refused(r)
    }
}

impl From<sqlx::Error> for AppError {
    fn from(e: sqlx::Error) -> Self {
        // PostgreSQL refuses text holding a NUL character (SQLite stores it): that is the
        // input's fault, not the server's.
        if let sqlx::Error::Database(db) = &e
            && db.code().as_deref() == Some("22021")
        {
            return AppError::Invalid(
                "text with a NUL character (\\u0000) cannot be stored or looked up".into(),
            );
        }
        if crate::store::db::is_busy(&e) {
            return AppError::Unavailable(DATABASE_BUSY.to_owned());
        }
        AppError::Internal(e.into())
    }
}

/// What a write that could not get the database's lock in time is told (with `503` and
/// `Retry-After` on the web).
pub const DATABASE_BUSY: &str = "the database is busy (another write held its lock too long); nothing was changed, retry in a moment";

impl From<super::heavy::HeavyBusy> for AppError {
    fn from(e: super::heavy::HeavyBusy) -> Self {
        AppError::Unavailable(e.to_string())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_answers_with_a_listed_code_and_typed_reasons_with_their_own() {
        let text = || "x".to_owned();
        let kinds = [
            AppError::NotFound(text()),
            AppError::Invalid(text()),
            AppError::Unauthenticated(text()),
            AppError::NotPermitted(text()),
            AppError::Conflict(text()),
            AppError::TooLarge(text()),
            AppError::UnsupportedFormat(text()),
            AppError::Rejected {
                message: text(),
                problems: Vec::new(),
            },
            AppError::LimitReached {
                message: text(),
                retry_after: None,
            },
            AppError::Unavailable(text()),
            AppError::internal("x"),
        ];
        let codes: Vec<&str> = kinds.iter().map(AppError::code).collect();
        assert_eq!(codes, AppError::KIND_CODES);
        for refusal in Refusal::examples() {
            let code = refusal.code();
            assert!(!AppError::KIND_CODES.contains(&code), "{code}");
            assert_eq!(AppError::from(refusal).code(), code);
        }
    }
}
