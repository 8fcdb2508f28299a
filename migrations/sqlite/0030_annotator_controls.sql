-- Annotator controls: a paused queue, and attention-check items mixed into every queue.

-- Annotators whose queue an admin paused: while a row is here the annotator can read their
-- queue but not open, save, answer or skip an item, and no balanced split gives them items.
-- Resuming removes the row; drafts and assignments are untouched either way.
CREATE TABLE annotator_pauses (
    annotator       INTEGER PRIMARY KEY REFERENCES annotators (id) ON DELETE CASCADE,
    -- The actor who paused, as the audit log writes it ("operator alice").
    paused_by       TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- A dataset's attention checks: how often the queue mixes one in (as gold_sets.rate).
CREATE TABLE attention_sets (
    dataset         INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    rate            INTEGER NOT NULL CHECK (rate >= 2),
    set_by          TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- The attention-check items and the instruction each one's question carries: 'keep' (put
-- the cards in the order the item page lists them) or 'reverse' (in the reverse of it). An
-- answer on one of them is judged against the instruction, never in the Human row or the
-- agreement report.
CREATE TABLE attention_items (
    item            INTEGER PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    dataset         INTEGER NOT NULL REFERENCES attention_sets (dataset) ON DELETE CASCADE,
    instruction     TEXT NOT NULL CHECK (instruction IN ('keep', 'reverse'))
);

CREATE INDEX attention_items_by_dataset ON attention_items (dataset);

-- 1 for an assignment the attention mix made: clearing the attention checks takes the
-- unfinished ones out of the queue. Annotators' pages never show it.
ALTER TABLE assignments ADD COLUMN attention INTEGER NOT NULL DEFAULT 0
    CHECK (attention IN (0, 1));
