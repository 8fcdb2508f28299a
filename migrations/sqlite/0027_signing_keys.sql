-- Signed statements (issue 39): the hub's public signing keys and a statement per scoring of a
-- submission. The secret keys are never stored here: each lives in a key file (beside a SQLite
-- database, or where `--signing-key` names it), so a backup of the database shares none.
--
-- Every key the hub ever signed with, so that old statements stay verifiable; `retired_at` is
-- set when a rotation replaced it (a retired key signs nothing new).
CREATE TABLE signing_keys (
    -- The order keys were listed in (several may be listed within one second).
    id                  INTEGER PRIMARY KEY AUTOINCREMENT,
    -- The first 16 hex digits of the SHA-256 of the raw public key.
    keyid               TEXT NOT NULL UNIQUE,
    algorithm           TEXT NOT NULL CHECK (algorithm = 'ed25519'),
    -- Base64 of the 32 raw public-key bytes.
    public_key          TEXT NOT NULL UNIQUE,
    created_at          TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    retired_at          TEXT
);

-- A DSSE envelope (JSON text) signed over what the hub computed for a submission; a rescore
-- adds a new one, and the newest is served.
CREATE TABLE submission_statements (
    id                  INTEGER PRIMARY KEY AUTOINCREMENT,
    submission          INTEGER NOT NULL REFERENCES submissions (id) ON DELETE CASCADE,
    keyid               TEXT NOT NULL REFERENCES signing_keys (keyid),
    envelope            TEXT NOT NULL,
    made_at             TEXT NOT NULL
);

CREATE INDEX submission_statements_newest ON submission_statements (submission, id);
