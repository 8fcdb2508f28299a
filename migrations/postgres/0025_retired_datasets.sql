-- Datasets a replacing import's cut-over retired (see the SQLite migration 0033 for the why):
-- their rows are deleted in short transactions after the cut-over.
CREATE TABLE retired_datasets (
    dataset     BIGINT PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    name        TEXT NOT NULL,
    retired_at  TEXT NOT NULL DEFAULT (to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"'))
);
