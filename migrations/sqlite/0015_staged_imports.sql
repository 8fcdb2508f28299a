-- Imports in progress. An import writes its new and changed items in batches, each its own
-- short transaction, under a hidden `datasets` row (`staging`) that no reader lists or looks up
-- by name; one short transaction at the end moves them into the dataset. The row records how
-- far the import got, so running the same import again resumes after its last committed batch.
CREATE TABLE staged_imports (
    id          INTEGER PRIMARY KEY,
    -- The dataset the import is for (one staged import per dataset).
    dataset     TEXT NOT NULL UNIQUE,
    staging     INTEGER NOT NULL UNIQUE REFERENCES datasets (id) ON DELETE CASCADE,
    -- The dataset's id when the import started (NULL: it did not exist); the cut-over refuses
    -- if that changed meanwhile.
    target      INTEGER,
    -- sha256 of the QA file and of the options that change what is written: a resume must
    -- match both.
    file_sha256 TEXT NOT NULL,
    options     TEXT NOT NULL,
    -- The run that writes the batches; another run of the same import takes it over.
    run_token   TEXT NOT NULL,
    -- Lines of the file, records among them and bytes consumed by committed batches.
    lines_done  INTEGER NOT NULL DEFAULT 0,
    rows_done   INTEGER NOT NULL DEFAULT 0,
    bytes_done  INTEGER NOT NULL DEFAULT 0,
    -- The import's report so far (JSON), written with each batch.
    report      TEXT NOT NULL DEFAULT '{}',
    started_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    updated_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

-- New signature tables for items the dataset already holds unchanged, applied at the cut-over.
CREATE TABLE staged_signatures (
    staged      INTEGER NOT NULL REFERENCES staged_imports (id) ON DELETE CASCADE,
    item_id     TEXT NOT NULL,
    source      TEXT NOT NULL CHECK (source IN ('scene_graph', 'action_text')),
    signatures  TEXT NOT NULL,
    PRIMARY KEY (staged, item_id)
);

-- A replacing import's cut-over deletes the replaced items, and with them what was made on
-- them; without these the delete scans each of these tables once per item.
CREATE INDEX submission_items_by_item ON submission_items (item);
CREATE INDEX annotations_by_item ON annotations (item);
CREATE INDEX drafts_by_item ON drafts (item);
CREATE INDEX agreement_samples_by_item ON agreement_samples (item);
CREATE INDEX model_run_items_by_item ON model_run_items (item);
