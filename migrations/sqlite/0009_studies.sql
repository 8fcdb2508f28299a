-- Ablation studies: a baseline dataset and variant datasets (grouped in families) that ask the
-- baseline's questions with other images. Items are aligned when a report is made, so a study
-- always reads the datasets as they are.
CREATE TABLE studies (
    id          INTEGER PRIMARY KEY,
    name        TEXT NOT NULL UNIQUE,
    baseline    INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    created_by  TEXT NOT NULL
);

CREATE TABLE study_variants (
    study       INTEGER NOT NULL REFERENCES studies (id) ON DELETE CASCADE,
    -- Order as the admin gave them: families are drawn in the order of their first variant.
    position    INTEGER NOT NULL,
    family      TEXT NOT NULL,
    label       TEXT NOT NULL,
    dataset     INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    PRIMARY KEY (study, position),
    UNIQUE (study, family, label),
    UNIQUE (study, dataset)
) WITHOUT ROWID;

CREATE INDEX study_variants_by_dataset ON study_variants (dataset);
