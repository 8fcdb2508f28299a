//! The hub's outbound clients, in a room of their own: what the hub sends to other services,
//! with the retries, backoff and `Retry-After` each needs, and nothing of what the hub does
//! with the replies.
//!
//! - [`endpoint`]: a model's OpenAI-compatible chat-completions endpoint (vLLM, an API), one
//!   item's request at a time within the in-flight window a run's requests share.
//! - [`hub`]: another hub's API, for a run against it (`enact-hub run --hub`).
//!
//! It may use [`enact_core`] (the requests' and replies' formats, backoff) and
//! [`enact_service`] (its errors); the use cases (`enact-app`'s `runs`) call it.

pub mod endpoint;
pub mod hub;
