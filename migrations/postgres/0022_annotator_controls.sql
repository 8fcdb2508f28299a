-- Annotator controls: paused queues and attention checks (see
-- migrations/sqlite/0030_annotator_controls.sql for what each column holds).
CREATE TABLE annotator_pauses (
    annotator       BIGINT PRIMARY KEY REFERENCES annotators (id) ON DELETE CASCADE,
    paused_by       TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"')
);

CREATE TABLE attention_sets (
    dataset         BIGINT PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    rate            BIGINT NOT NULL CHECK (rate >= 2),
    set_by          TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"')
);

CREATE TABLE attention_items (
    item            BIGINT PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    dataset         BIGINT NOT NULL REFERENCES attention_sets (dataset) ON DELETE CASCADE,
    instruction     TEXT NOT NULL CHECK (instruction IN ('keep', 'reverse'))
);

CREATE INDEX attention_items_by_dataset ON attention_items (dataset);

ALTER TABLE assignments ADD COLUMN attention BOOLEAN NOT NULL DEFAULT FALSE;
