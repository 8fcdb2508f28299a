-- Human annotation: annotator accounts, their sessions, item assignments, autosaved drafts and
-- answers (see src/annotation/ and src/web/annotate.rs).

CREATE TABLE annotators (
    id              INTEGER PRIMARY KEY,
    name            TEXT NOT NULL UNIQUE,
    is_admin        INTEGER NOT NULL DEFAULT 0 CHECK (is_admin IN (0, 1)),
    -- argon2 PHC string; NULL until the invite has been used.
    password_hash   TEXT,
    -- sha256 (hex) of the single-use invite token; NULL once used.
    invite_hash     TEXT UNIQUE,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- Login sessions. Only the sha256 of the cookie value is stored.
CREATE TABLE sessions (
    token_hash      TEXT PRIMARY KEY,
    annotator       INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    -- Synchronizer token every state-changing request of this session must carry.
    csrf_token      TEXT NOT NULL,
    expires_at_ms   INTEGER NOT NULL
) WITHOUT ROWID;

CREATE INDEX sessions_by_annotator ON sessions (annotator);

CREATE TABLE assignments (
    annotator       INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    item            INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    -- Queue order within the annotator's assignments.
    position        INTEGER NOT NULL,
    PRIMARY KEY (annotator, item)
) WITHOUT ROWID;

CREATE INDEX assignments_by_item ON assignments (item);

-- The half-placed answer of an item being worked on, saved on every change.
CREATE TABLE drafts (
    annotator       INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    item            INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    -- JSON list of L-1 slots: a label or null.
    slots           TEXT NOT NULL,
    -- JSON counters (placements, swaps, clears, undos) and the undo history.
    state           TEXT NOT NULL,
    started_at_ms   INTEGER NOT NULL,
    first_placement_at_ms INTEGER,
    updated_at_ms   INTEGER NOT NULL,
    PRIMARY KEY (annotator, item)
) WITHOUT ROWID;

-- One finished item per annotator: an answer, or a skip or flag with its reason.
CREATE TABLE annotations (
    annotator       INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    item            INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    outcome         TEXT NOT NULL CHECK (outcome IN ('answered', 'skipped', 'flagged')),
    -- JSON permutation of 1..L-1 (ENACT's answer) when answered.
    answer          TEXT,
    reason          TEXT NOT NULL DEFAULT '',
    time_on_item_ms INTEGER NOT NULL,
    time_to_first_placement_ms INTEGER,
    placements      INTEGER NOT NULL,
    swaps           INTEGER NOT NULL,
    clears          INTEGER NOT NULL,
    undos           INTEGER NOT NULL,
    finished_at     TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    PRIMARY KEY (annotator, item),
    CHECK ((outcome = 'answered') = (answer IS NOT NULL))
) WITHOUT ROWID;
