-- Real-world episodes: recorded frames a curator turns into items by marking key frames and
-- drawing each one's scene graph (issue 28).

CREATE TABLE episodes (
    id              INTEGER PRIMARY KEY,
    name            TEXT NOT NULL UNIQUE,
    -- The scene it was recorded in ("kitchen"), carried to the datasets made from it.
    scene           TEXT NOT NULL DEFAULT '',
    created_by      TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    -- The graphs file (core::episode::EpisodeGraphs as JSON) an admin chose for export;
    -- NULL until one is chosen.
    resolved_graphs TEXT,
    resolved_by     TEXT
);

-- The episode's frames in order, each stored as a frame like any item's, with a small copy
-- for the filmstrip.
CREATE TABLE episode_frames (
    episode     INTEGER NOT NULL REFERENCES episodes (id) ON DELETE CASCADE,
    position    INTEGER NOT NULL, -- 0-based, the `frame` of the graphs file
    file_name   TEXT NOT NULL,    -- as imported, for people
    frame       INTEGER NOT NULL REFERENCES frames (id),
    thumbnail   INTEGER NOT NULL REFERENCES frames (id),
    PRIMARY KEY (episode, position)
) WITHOUT ROWID;

-- Each curator's key frames and graphs of an episode, as one graphs file (JSON).
CREATE TABLE episode_graphs (
    episode     INTEGER NOT NULL REFERENCES episodes (id) ON DELETE CASCADE,
    curator     TEXT NOT NULL,
    graphs      TEXT NOT NULL,
    updated_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    PRIMARY KEY (episode, curator)
) WITHOUT ROWID;

-- Where a dataset's items come from: 'simulation' (BEHAVIOR replays, the synthetic world) or
-- 'real' (an exported episode), and the scene named at export. `source` already holds the
-- path an import read from.
ALTER TABLE datasets ADD COLUMN origin TEXT NOT NULL DEFAULT 'simulation'
    CHECK (origin IN ('simulation', 'real'));
ALTER TABLE datasets ADD COLUMN scene TEXT NOT NULL DEFAULT '';
