-- Datasets, their items, and the key frames the items show.

CREATE TABLE datasets (
    id          INTEGER PRIMARY KEY,
    name        TEXT NOT NULL UNIQUE,
    created_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    -- Where the last import read from, for people (not used by the code).
    source      TEXT NOT NULL DEFAULT ''
);

-- Frames are stored once per distinct PNG byte content: one key frame appears in many items.
CREATE TABLE frames (
    id          INTEGER PRIMARY KEY,
    sha256      TEXT NOT NULL UNIQUE,
    width       INTEGER NOT NULL,
    height      INTEGER NOT NULL,
    png         BLOB NOT NULL
);

CREATE TABLE items (
    id              INTEGER PRIMARY KEY,
    dataset_id      INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    -- ENACT's item id, unique within a dataset.
    item_id         TEXT NOT NULL,
    item_type       TEXT NOT NULL,
    direction       TEXT NOT NULL CHECK (direction IN ('forward', 'inverse')),
    step_length     INTEGER NOT NULL CHECK (step_length BETWEEN 3 AND 10),
    task_name       TEXT NOT NULL,
    key_frame_ids   TEXT NOT NULL, -- JSON list of decimal strings, chronological
    question        TEXT NOT NULL,
    actions         TEXT NOT NULL, -- JSON list, in the order the question shows them
    gt_answer       TEXT NOT NULL, -- JSON list: a permutation of 1..L-1
    -- sha256 over the record's fields and its image bytes; equal hash = same item.
    content_hash    TEXT NOT NULL,
    -- 1-based line of the source file the item came from.
    source_line     INTEGER NOT NULL,
    UNIQUE (dataset_id, item_id)
);

CREATE INDEX items_by_kind ON items (dataset_id, direction, step_length);
CREATE INDEX items_by_task ON items (dataset_id, task_name);

CREATE TABLE item_images (
    item        INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    position    INTEGER NOT NULL, -- index into the record's `images` list
    path        TEXT NOT NULL,    -- as written in the record, relative to the release root
    frame       INTEGER NOT NULL REFERENCES frames (id),
    PRIMARY KEY (item, position)
) WITHOUT ROWID;

CREATE INDEX item_images_by_frame ON item_images (frame);

-- Bumped by every write that changes what items look like, so running servers know when to
-- drop their caches (imports run in another process).
CREATE TABLE content_generation (
    id      INTEGER PRIMARY KEY CHECK (id = 1),
    value   INTEGER NOT NULL
);
INSERT INTO content_generation (id, value) VALUES (1, 0);
