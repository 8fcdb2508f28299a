//! API tokens: their format, hashing, constant-time comparison, roles and scopes (pure).
//!
//! A token reads `ehub_{prefix}_{secret}`. The prefix is its public part (shown by
//! `token list`, used to find the row); only the SHA-256 of the whole token is stored, so the
//! database never holds a usable secret.

use std::fmt;

use rand::RngCore;
use serde::Serialize;
use sha2::{Digest, Sha256};

const TOKEN_PREFIX: &str = "ehub_";
/// Hex digits of the public part.
const PREFIX_HEX: usize = 12;
/// Random bytes of the secret part (256 bits).
const SECRET_BYTES: usize = 32;

/// What a token may do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scope {
    /// Post submissions.
    Submit,
    /// Read the submissions of the token's own account.
    ReadOwn,
    /// Manage accounts, tokens, datasets and leaderboard rows; read every submission.
    Admin,
}

impl Scope {
    pub fn as_str(self) -> &'static str {
        match self {
            Scope::Submit => "submit",
            Scope::ReadOwn => "read_own",
            Scope::Admin => "admin",
        }
    }

    pub fn parse(s: &str) -> Option<Scope> {
        match s {
            "submit" => Some(Scope::Submit),
            "read_own" => Some(Scope::ReadOwn),
            "admin" => Some(Scope::Admin),
            _ => None,
        }
    }
}

/// The kind of account a token belongs to; it fixes the token's scopes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    Submitter,
    Admin,
}

impl Role {
    pub fn as_str(self) -> &'static str {
        match self {
            Role::Submitter => "submitter",
            Role::Admin => "admin",
        }
    }

    pub fn parse(s: &str) -> Option<Role> {
        match s {
            "submitter" => Some(Role::Submitter),
            "admin" => Some(Role::Admin),
            _ => None,
        }
    }

    pub fn scopes(self) -> &'static [Scope] {
        match self {
            Role::Submitter => &[Scope::Submit, Scope::ReadOwn],
            Role::Admin => &[Scope::Admin, Scope::Submit, Scope::ReadOwn],
        }
    }
}

/// Scopes as stored: comma-separated.
pub fn scopes_to_text(scopes: &[Scope]) -> String {
    scopes
        .iter()
        .map(|s| s.as_str())
        .collect::<Vec<_>>()
        .join(",")
}

/// Unknown names are dropped: a token never gains a scope from a typo.
pub fn scopes_from_text(text: &str) -> Vec<Scope> {
    text.split(',')
        .filter_map(|s| Scope::parse(s.trim()))
        .collect()
}

/// A freshly generated token. The secret exists only in this value; print it once.
pub struct NewToken {
    pub token: String,
    pub prefix: String,
    pub hash: String,
}

impl fmt::Debug for NewToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("NewToken")
            .field("prefix", &self.prefix)
            .finish_non_exhaustive()
    }
}

impl NewToken {
    pub fn generate() -> NewToken {
        let mut rng = rand::rng();
        let mut public = [0u8; PREFIX_HEX / 2];
        let mut secret = [0u8; SECRET_BYTES];
        rng.fill_bytes(&mut public);
        rng.fill_bytes(&mut secret);
        let prefix = hex::encode(public);
        let token = format!("{TOKEN_PREFIX}{prefix}_{}", hex::encode(secret));
        NewToken {
            hash: token_hash(&token),
            prefix,
            token,
        }
    }

    /// A token chosen by the operator (ENACT_HUB_ADMIN_TOKEN): any text of 16+ characters.
    /// Its prefix is derived from its hash, so it can be found without storing it.
    pub fn from_operator(token: &str) -> Result<NewToken, String> {
        if token.chars().count() < 16 {
            return Err("the admin token must be at least 16 characters long".to_owned());
        }
        let hash = token_hash(token);
        Ok(NewToken {
            prefix: operator_prefix(&hash),
            hash,
            token: token.to_owned(),
        })
    }
}

fn operator_prefix(hash: &str) -> String {
    format!("op{}", &hash[..PREFIX_HEX - 2])
}

pub fn token_hash(token: &str) -> String {
    hex::encode(Sha256::digest(token.as_bytes()))
}

/// The lookup prefix of a presented token: the public part of a generated token, or the
/// hash-derived prefix of an operator-chosen one.
pub fn lookup_prefix(token: &str) -> String {
    if let Some(rest) = token.strip_prefix(TOKEN_PREFIX)
        && let Some((prefix, secret)) = rest.split_once('_')
        && prefix.len() == PREFIX_HEX
        && prefix.bytes().all(|b| b.is_ascii_hexdigit())
        && !secret.is_empty()
    {
        return prefix.to_owned();
    }
    operator_prefix(&token_hash(token))
}

/// Compares two byte strings in time that depends only on their lengths.
pub fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut diff = 0u8;
    for (x, y) in a.iter().zip(b) {
        diff |= x ^ y;
    }
    diff == 0
}

/// Whether `presented` is the token whose hash is `stored_hash`.
pub fn token_matches(presented: &str, stored_hash: &str) -> bool {
    constant_time_eq(token_hash(presented).as_bytes(), stored_hash.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_tokens_are_distinct_and_found_by_their_prefix() {
        let a = NewToken::generate();
        let b = NewToken::generate();
        assert_ne!(a.token, b.token);
        assert!(a.token.starts_with("ehub_"));
        assert_eq!(lookup_prefix(&a.token), a.prefix);
        assert!(token_matches(&a.token, &a.hash));
        assert!(!token_matches(&b.token, &a.hash));
        assert!(!format!("{a:?}").contains(&a.token));
    }

    #[test]
    fn operator_tokens_need_length_and_are_found_by_hash() {
        assert!(NewToken::from_operator("short").is_err());
        let t = NewToken::from_operator("a-long-operator-secret").expect("long enough");
        assert_eq!(lookup_prefix("a-long-operator-secret"), t.prefix);
        assert!(token_matches("a-long-operator-secret", &t.hash));
    }

    #[test]
    fn constant_time_eq_compares_content_and_length() {
        assert!(constant_time_eq(b"abc", b"abc"));
        assert!(!constant_time_eq(b"abc", b"abd"));
        assert!(!constant_time_eq(b"abc", b"abcd"));
    }

    #[test]
    fn scopes_round_trip_and_ignore_unknown_names() {
        let text = scopes_to_text(Role::Admin.scopes());
        assert_eq!(scopes_from_text(&text), Role::Admin.scopes());
        assert_eq!(scopes_from_text("submit,root"), vec![Scope::Submit]);
    }
}
