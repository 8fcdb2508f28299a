-- Hidden test sets that resist overfitting (issue 39): a dataset whose answers are hidden split
-- into a public part, whose figures the leaderboard shows while the challenge runs, and a
-- private part revealed at a deadline (`reveal_at`) or by hand. Items are drawn into the parts
-- by `enact_core::challenge::draw_split` (seeded, stratified by direction and step length); a
-- split is final. `revealed_at` is set once, when the private part is revealed.
CREATE TABLE challenges (
    dataset             INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    seed                INTEGER NOT NULL,
    public_share        REAL NOT NULL CHECK (public_share > 0 AND public_share < 1),
    reveal_at           TEXT,
    revealed_at         TEXT,
    -- `deadline` (reached, recorded by the first reader after it) or `hand` (an admin).
    revealed_by         TEXT CHECK (revealed_by IN ('deadline', 'hand')),
    -- How many submissions an account may select for the final ranking; NULL: no limit.
    selection_limit     INTEGER CHECK (selection_limit IS NULL OR selection_limit > 0),
    -- The actor who split it, as the audit log writes it.
    split_by            TEXT NOT NULL,
    created_at          TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    CHECK ((revealed_at IS NULL) = (revealed_by IS NULL))
);

-- The part of each item of a split dataset (items imported after the split have none).
CREATE TABLE challenge_items (
    item                INTEGER PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    dataset             INTEGER NOT NULL REFERENCES challenges (dataset) ON DELETE CASCADE,
    part                TEXT NOT NULL CHECK (part IN ('public', 'private'))
);

CREATE INDEX challenge_items_by_dataset ON challenge_items (dataset, part);

-- Submissions their accounts selected for a split dataset's final ranking; a later selection
-- has a larger id (the selection rule keeps the latest ones when a limit is lowered).
CREATE TABLE challenge_selections (
    id                  INTEGER PRIMARY KEY AUTOINCREMENT,
    submission          INTEGER NOT NULL UNIQUE REFERENCES submissions (id) ON DELETE CASCADE,
    selected_at         TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);
