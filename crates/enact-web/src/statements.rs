//! Signed statements over HTTP: a submission's statement, the hub's public keys, and the
//! admin's key rotation (`app::statements`, `app::signing`).

use axum::extract::State;
use schemars::JsonSchema;
use serde::Serialize;

use super::auth::TokenCaller;
use super::error::ApiError;
use super::extract::{Json, Path};
use super::openapi::{ApiRoute, Verb};
use super::{AppError, AppState};
use crate::app::{challenge, signing, statements, submissions};
use crate::core::credentials::Scope;
use crate::core::statement::{Envelope, PublishedKey, PublishedKeys};

pub fn routes() -> Vec<ApiRoute> {
    vec![
        ApiRoute::new(
            Verb::Get,
            "/submissions/{id}/statement",
            get_statement,
            "A submission's signed statement",
        )
        .describe(
            "A DSSE envelope (`payloadType` `application/vnd.enact-hub.statement+json`, \
             `payload` base64, `signatures` with `keyid` and `sig`) signed with the hub's \
             Ed25519 key over DSSE's pre-authentication encoding. The payload (JSON) names the \
             hub, the submission, the dataset with the SHA-256 of its items, the SHA-256 of the \
             answers as uploaded, a SHA-256 over the per-item verdicts, the metric version, \
             policy, provenance, the scores as `GET /api/v1/submissions/{id}` reports them, \
             and when it was made; README \"How to check a result\" defines each digest. The \
             newest statement is served (a rescore makes a new one). Check it offline with \
             `enact-hub verify` or `enact_hub.verify` against `GET /api/v1/keys`. Readable by \
             whoever may read the submission; on a dataset split for a challenge, only by an \
             admin until the private part is revealed (409 before: the statement's scores are \
             over every item).",
        )
        .bearer(Scope::ReadOwn)
        .responds_json::<Envelope>(200, "The statement (a DSSE envelope).")
        .errors(&[401, 403, 404, 409]),
        ApiRoute::new(
            Verb::Get,
            "/keys",
            list_keys,
            "The hub's public signing keys",
        )
        .describe(
            "Every Ed25519 key the hub signed statements with: `keyid` (the first 16 hex \
                 digits of the SHA-256 of the raw key), `algorithm` (`ed25519`), `public_key` \
                 (base64 of the 32 raw bytes), `created_at`, and `retired_at` once a rotation \
                 replaced it (a retired key signs nothing new and still verifies what it \
                 signed). Save this list beside a statement to check it offline later.",
        )
        .responds_json::<PublishedKeys>(200, "The keys, oldest first.")
        .errors(&[]),
        ApiRoute::new(
            Verb::Post,
            "/admin/keys/rotate",
            rotate_key,
            "Rotate the statement-signing key",
        )
        .describe(
            "Makes a new signing key (written to the server's key file, never to the \
             database), lists its public key and retires every other key: new statements are \
             signed with it, old ones keep verifying against the listed keys. Audited as \
             `key.rotate`. The same as `enact-hub keys rotate`.",
        )
        .bearer(Scope::Admin)
        .responds_json::<RotatedView>(200, "The new key and the keys it retired.")
        .errors(&[401, 403]),
    ]
}

async fn get_statement(
    State(state): State<AppState>,
    Path(id): Path<String>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<Envelope>, ApiError> {
    let row = submissions::readable(&state.hub, &caller, &id).await?;
    if let Some(why) = challenge::whole_figures_withheld(&state.hub, &caller, &row).await? {
        return Err(ApiError(AppError::Conflict(why)));
    }
    Ok(Json(statements::newest_or_make(&state.hub, &row).await?))
}

async fn list_keys(State(state): State<AppState>) -> Result<Json<PublishedKeys>, ApiError> {
    Ok(Json(signing::public_keys(&state.hub).await?))
}

/// What a rotation did.
#[derive(Serialize, JsonSchema)]
struct RotatedView {
    /// The key that signs from now on.
    key: PublishedKey,
    /// The ids of the keys it retired.
    retired: Vec<String>,
}

async fn rotate_key(
    State(state): State<AppState>,
    TokenCaller(caller): TokenCaller,
) -> Result<Json<RotatedView>, ApiError> {
    let rotated = signing::rotate(&state.hub, &caller.actor()).await?;
    Ok(Json(RotatedView {
        key: rotated.key,
        retired: rotated.retired,
    }))
}
