-- Annotator quality control: gold items mixed into every annotator's queue, and annotators
-- whose answers an admin keeps out of the Human row and the agreement report.

-- A dataset's gold set: how its items were chosen and how often the queue mixes one in.
CREATE TABLE gold_sets (
    dataset         INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    -- One gold item in every `rate` queue items (rate - 1 ordinary items, then a gold one).
    rate            INTEGER NOT NULL CHECK (rate >= 2),
    -- 'share': a seeded random share of the items; 'list': the ids an admin gave.
    chosen_by       TEXT NOT NULL CHECK (chosen_by IN ('share', 'list')),
    share           REAL,
    -- The sampling seed (a u64 stored bit for bit in SQLite's signed integer).
    seed            INTEGER,
    -- The actor who set it, as the audit log writes it ("operator alice").
    set_by          TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    CHECK ((chosen_by = 'share') = (share IS NOT NULL AND seed IS NOT NULL))
);

-- The gold items. An answer on one of them counts for its annotator's quality and never in
-- the Human row or the agreement report.
CREATE TABLE gold_items (
    item            INTEGER PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    dataset         INTEGER NOT NULL REFERENCES gold_sets (dataset) ON DELETE CASCADE
);

CREATE INDEX gold_items_by_dataset ON gold_items (dataset);

-- 1 for an assignment the gold mix made (not the annotator's own share): clearing the gold set
-- takes the unfinished ones out of the queue. Annotators' pages never show it.
ALTER TABLE assignments ADD COLUMN gold INTEGER NOT NULL DEFAULT 0 CHECK (gold IN (0, 1));

-- Annotators whose answers on a dataset leave the Human row and the agreement report (kept,
-- not deleted: removing the row brings them back).
CREATE TABLE annotator_exclusions (
    dataset         INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    annotator       INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    excluded_by     TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    PRIMARY KEY (dataset, annotator)
) WITHOUT ROWID;
