-- Results a paper published, entered as data (issue 37): one row per dataset, model and source
-- (a paper, a table label or a URL), with the model's category, family and size, and its task
-- and pairwise accuracy per direction and step length as `enact_core::paper` cells (JSON
-- objects keyed `forward_3` .. `inverse_10`, values in percent as printed). They are shown on
-- the leaderboard as their own kind of row, never ranked against the hub's scored rows.
CREATE TABLE reported_results (
    id                  INTEGER PRIMARY KEY AUTOINCREMENT,
    dataset             INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    model               TEXT NOT NULL CHECK (length(model) > 0),
    source              TEXT NOT NULL CHECK (length(source) > 0),
    -- `proprietary`, `open-weight`, `human`, or a name an admin gave.
    category            TEXT NOT NULL CHECK (length(category) > 0),
    family              TEXT,
    size                TEXT,
    task_accuracy       TEXT NOT NULL,
    pairwise_accuracy   TEXT NOT NULL,
    -- The actor who entered it, as the audit log writes it ("operator alice").
    added_by            TEXT NOT NULL,
    created_at          TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    CONSTRAINT reported_results_model_source UNIQUE (dataset, model, source)
);

-- What the hub's own leaderboard rows of a model on a dataset say about it: its category,
-- family, size and a link. Per dataset, as submissions and their owners are: the account that
-- submitted the model to the dataset may edit it, and the same name on another dataset may be
-- another account's model.
CREATE TABLE model_metadata (
    dataset             INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    model               TEXT NOT NULL,
    category            TEXT,
    family              TEXT,
    size                TEXT,
    link                TEXT,
    updated_by          TEXT NOT NULL,
    updated_at          TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    PRIMARY KEY (dataset, model)
);
