-- Annotator quality control (see migrations/sqlite/0013_annotator_quality.sql for what each
-- column holds).
CREATE TABLE gold_sets (
    dataset         BIGINT PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    rate            BIGINT NOT NULL CHECK (rate >= 2),
    chosen_by       TEXT NOT NULL CHECK (chosen_by IN ('share', 'list')),
    share           DOUBLE PRECISION,
    seed            BIGINT,
    set_by          TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"'),
    CHECK ((chosen_by = 'share') = (share IS NOT NULL AND seed IS NOT NULL))
);

CREATE TABLE gold_items (
    item            BIGINT PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    dataset         BIGINT NOT NULL REFERENCES gold_sets (dataset) ON DELETE CASCADE
);

CREATE INDEX gold_items_by_dataset ON gold_items (dataset);

ALTER TABLE assignments ADD COLUMN gold BOOLEAN NOT NULL DEFAULT FALSE;

CREATE TABLE annotator_exclusions (
    dataset         BIGINT NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    annotator       BIGINT NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    excluded_by     TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"'),
    PRIMARY KEY (dataset, annotator)
);
