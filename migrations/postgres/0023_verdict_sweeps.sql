-- A replacing import's cut-over leaves the replaced items' verdicts, deleted afterwards one
-- submission per short transaction (see the SQLite migration 0031 for the why).
CREATE TABLE verdict_sweeps (
    dataset       BIGINT PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    generation    BIGINT NOT NULL DEFAULT 1,
    swept_through BIGINT NOT NULL DEFAULT 0
);
