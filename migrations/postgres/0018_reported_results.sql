-- As SQLite's 0026: results a paper published, and the hub's own models' metadata.
CREATE TABLE reported_results (
    id                  BIGSERIAL PRIMARY KEY,
    dataset             BIGINT NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    model               TEXT NOT NULL CHECK (length(model) > 0),
    source              TEXT NOT NULL CHECK (length(source) > 0),
    category            TEXT NOT NULL CHECK (length(category) > 0),
    family              TEXT,
    size                TEXT,
    task_accuracy       TEXT NOT NULL,
    pairwise_accuracy   TEXT NOT NULL,
    added_by            TEXT NOT NULL,
    created_at          TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"'),
    CONSTRAINT reported_results_model_source UNIQUE (dataset, model, source)
);

CREATE TABLE model_metadata (
    dataset             BIGINT NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    model               TEXT NOT NULL,
    category            TEXT,
    family              TEXT,
    size                TEXT,
    link                TEXT,
    updated_by          TEXT NOT NULL,
    updated_at          TEXT NOT NULL DEFAULT to_char(now() AT TIME ZONE 'UTC', 'YYYY-MM-DD"T"HH24:MI:SS"Z"'),
    PRIMARY KEY (dataset, model)
);
