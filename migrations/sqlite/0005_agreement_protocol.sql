-- The cross-annotation protocol of ENACT's appendix B.1.2: why each assignment exists, and the
-- one protocol round a dataset may have (its k, seed and the items it drew).

-- primary: the annotator's own share (split or id list); agreement: another annotator's item,
-- given again by the protocol. Annotators' pages never show the kind.
ALTER TABLE assignments ADD COLUMN kind TEXT NOT NULL DEFAULT 'primary'
    CHECK (kind IN ('primary', 'agreement'));

-- At most one round per dataset: a second run is refused, so the sample stays the one recorded.
CREATE TABLE agreement_rounds (
    dataset         INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    items_per_cell  INTEGER NOT NULL CHECK (items_per_cell >= 1),
    -- The sampling seed, as given (a u64 stored bit for bit in SQLite's signed integer).
    seed            INTEGER NOT NULL,
    started_by      INTEGER REFERENCES annotators (id) ON DELETE SET NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- The items a round drew, each with the annotator whose primary answer it was.
CREATE TABLE agreement_samples (
    dataset          INTEGER NOT NULL REFERENCES agreement_rounds (dataset) ON DELETE CASCADE,
    item             INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    source_annotator INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    PRIMARY KEY (dataset, item)
) WITHOUT ROWID;
