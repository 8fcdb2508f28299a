-- Accounts, API tokens, submissions and their per-item verdicts, and per-dataset settings.

-- A person or team that submits; admins manage everything else.
CREATE TABLE accounts (
    id          INTEGER PRIMARY KEY,
    name        TEXT NOT NULL UNIQUE,
    role        TEXT NOT NULL CHECK (role IN ('submitter', 'admin')),
    created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- The secret is never stored: only its SHA-256. `prefix` is the token's public part, used to
-- find the row before the hashes are compared in constant time.
CREATE TABLE api_tokens (
    id          INTEGER PRIMARY KEY,
    account     INTEGER NOT NULL REFERENCES accounts (id) ON DELETE CASCADE,
    prefix      TEXT NOT NULL UNIQUE,
    token_hash  TEXT NOT NULL,
    -- Comma-separated: submit, read_own, admin.
    scopes      TEXT NOT NULL,
    -- NULL = the server's default quota.
    daily_quota INTEGER,
    total_quota INTEGER,
    created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    revoked_at  TEXT
);

-- One row per submission request that passed authentication, accepted or rejected: quotas
-- count these.
CREATE TABLE submission_attempts (
    id          INTEGER PRIMARY KEY,
    token       INTEGER NOT NULL REFERENCES api_tokens (id) ON DELETE CASCADE,
    created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

CREATE INDEX submission_attempts_by_token ON submission_attempts (token, created_at);

-- Whether submitters may see a dataset's ground truth and per-item correctness.
CREATE TABLE dataset_settings (
    dataset     INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    answers     TEXT NOT NULL DEFAULT 'hidden' CHECK (answers IN ('public', 'hidden'))
);

CREATE TABLE submissions (
    id              INTEGER PRIMARY KEY,
    dataset         INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    account         INTEGER NOT NULL REFERENCES accounts (id) ON DELETE CASCADE,
    token           INTEGER NOT NULL REFERENCES api_tokens (id) ON DELETE CASCADE,
    idempotency_key TEXT,
    -- SHA-256 of the body, so a reused Idempotency-Key with another body is refused.
    body_sha256     TEXT NOT NULL,
    model           TEXT NOT NULL,
    description     TEXT NOT NULL DEFAULT '',
    url             TEXT NOT NULL DEFAULT '',
    prompt_version  TEXT NOT NULL DEFAULT '',
    notes           TEXT NOT NULL DEFAULT '',
    policy          TEXT NOT NULL DEFAULT 'strict',
    status          TEXT NOT NULL DEFAULT 'scored' CHECK (status IN ('scored')),
    -- published: on the leaderboard; hidden: off it until an admin shows it again;
    -- withdrawn: off it for good (kept for the record).
    visibility      TEXT NOT NULL DEFAULT 'published'
                    CHECK (visibility IN ('published', 'hidden', 'withdrawn')),
    baseline        INTEGER NOT NULL DEFAULT 0 CHECK (baseline IN (0, 1)),
    -- The serialised SubmissionScores (report, coverage, bootstrap intervals).
    scores          TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    UNIQUE (token, idempotency_key)
);

CREATE INDEX submissions_by_dataset ON submissions (dataset, visibility);

-- One row per dataset item: what was answered and how it was judged.
CREATE TABLE submission_items (
    submission          INTEGER NOT NULL REFERENCES submissions (id) ON DELETE CASCADE,
    item                INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    -- Line (or array element) of the body the answer came from; NULL when missing.
    line                INTEGER,
    raw_answer          TEXT,    -- the `answer` value as JSON, as submitted
    permutation         TEXT,    -- JSON list, when the answer could be read
    outcome             TEXT NOT NULL CHECK (outcome IN ('scored', 'unparseable', 'missing')),
    failure             TEXT,    -- why the answer could not be read
    exact_match         INTEGER NOT NULL,
    semantic_match      INTEGER NOT NULL,
    task_accuracy       INTEGER NOT NULL,
    pairwise_accuracy   REAL,
    PRIMARY KEY (submission, item)
) WITHOUT ROWID;
