//! Who may do what, and the secrets that prove it (pure): API tokens (format, hashing,
//! constant-time comparison), roles and scopes; the random tokens of annotator sessions,
//! invites and CSRF; passwords; and the naming rules of accounts.
//!
//! An API token reads `ehub_{prefix}_{secret}`. The prefix is its public part (shown by
//! `token list`, used to find the row). Only SHA-256 hashes of tokens are stored, so the
//! database never holds a usable secret.

use schemars::JsonSchema;
use std::fmt;

use argon2::Argon2;
use argon2::password_hash::{PasswordHash, PasswordHasher, PasswordVerifier, SaltString};
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize, JsonSchema)]
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

impl fmt::Display for Role {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
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

/// A token that authenticated a request, with its account: who a use case acts for.
#[derive(Debug, Clone)]
pub struct Caller {
    pub token_id: i64,
    pub account_id: i64,
    pub account_name: String,
    pub scopes: Vec<Scope>,
    pub daily_quota: Option<i64>,
    pub total_quota: Option<i64>,
}

impl Caller {
    /// Who this caller is in the audit log.
    pub fn actor(&self) -> crate::audit::Actor {
        crate::audit::Actor::Account(self.account_name.clone())
    }

    pub fn has(&self, scope: Scope) -> bool {
        self.scopes.contains(&scope)
    }
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

/// What the store keeps of any token: its SHA-256, so a leaked database opens nothing.
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

/// Shortest password accepted when an invite is used.
pub const MIN_PASSWORD_CHARS: usize = 10;

/// A fresh random token (256 bits, hex): session cookies, invite links, CSRF tokens.
pub fn random_token() -> String {
    let mut bytes = [0u8; 32];
    rand::rng().fill_bytes(&mut bytes);
    hex::encode(bytes)
}

/// argon2id with the crate's default cost. Slow on purpose: call it from `spawn_blocking`.
pub fn hash_password(password: &str) -> Result<String, argon2::password_hash::Error> {
    let mut salt = [0u8; 16];
    rand::rng().fill_bytes(&mut salt);
    let salt = SaltString::encode_b64(&salt)?;
    Ok(Argon2::default()
        .hash_password(password.as_bytes(), &salt)?
        .to_string())
}

/// Whether `password` matches a stored PHC string. Slow on purpose: call it from `spawn_blocking`.
pub fn verify_password(password: &str, stored: &str) -> bool {
    PasswordHash::new(stored).is_ok_and(|hash| {
        Argon2::default()
            .verify_password(password.as_bytes(), &hash)
            .is_ok()
    })
}

/// The length in characters of a new password too short to take (under
/// [`MIN_PASSWORD_CHARS`]); `None` when it is long enough.
pub fn too_short_password(password: &str) -> Option<usize> {
    let chars = password.chars().count();
    (chars < MIN_PASSWORD_CHARS).then_some(chars)
}

/// The name of an API account (a person or team), trimmed: 1 to 100 characters.
pub fn account_name(name: &str) -> Result<&str, String> {
    let name = name.trim();
    if name.is_empty() || name.chars().count() > 100 {
        return Err("an account name has 1 to 100 characters".to_owned());
    }
    Ok(name)
}

/// The login name of an annotator, trimmed. Names are shown on pages and typed at login, so
/// they stay plain: 1 to 64 letters, digits, `.`, `_` and `-`.
pub fn annotator_name(name: &str) -> Result<&str, String> {
    plain_name(name, "annotator", 64)
}

/// A name that goes into pages, URLs and file names as it is, trimmed: 1 to `max` letters,
/// digits, `.`, `_` and `-`. `kind` names it in messages ("annotator", "study").
pub fn plain_name<'a>(name: &'a str, kind: &str, max: usize) -> Result<&'a str, String> {
    let name = name.trim();
    if name.is_empty() || name.chars().count() > max {
        let article = if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        };
        return Err(format!("{article} {kind} name has 1 to {max} characters"));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Err(format!(
            "{kind} name '{name}': character {c:?} is not allowed (letters, digits, . _ -)"
        ));
    }
    Ok(name)
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

    #[test]
    fn passwords_and_random_tokens() {
        let hash = hash_password("correct horse").expect("hash");
        assert!(verify_password("correct horse", &hash));
        assert!(!verify_password("wrong horse", &hash));
        assert!(!verify_password("correct horse", "not a phc string"));
        assert_eq!(too_short_password("short"), Some(5));
        assert_eq!(too_short_password("ninechars"), Some(9));
        assert_eq!(too_short_password("long enough"), None);
        let (a, b) = (random_token(), random_token());
        assert_eq!(a.len(), 64);
        assert_ne!(a, b);
        assert!(constant_time_eq(a.as_bytes(), a.clone().as_bytes()));
        assert!(!constant_time_eq(a.as_bytes(), b.as_bytes()));
        assert_ne!(token_hash(&a), a);
    }

    #[test]
    fn names_follow_one_rule_each() {
        assert_eq!(account_name("  team-a "), Ok("team-a"));
        assert!(account_name("   ").is_err());
        assert!(account_name(&"x".repeat(101)).is_err());
        assert_eq!(annotator_name(" ann.o_t-1 "), Ok("ann.o_t-1"));
        let e = annotator_name("ann ot").expect_err("a space is refused");
        assert!(e.contains("' '"), "{e}");
        assert!(annotator_name(&"a".repeat(65)).is_err());
    }
}
