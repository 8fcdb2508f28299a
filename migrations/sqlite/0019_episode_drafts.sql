-- A curator's unsaved key frames and graphs of an episode, kept on every change in the
-- episode page's editor so that a reload resumes where the curator was. Saving checks them
-- and stores them in episode_graphs; the draft is then removed.
CREATE TABLE episode_drafts (
    episode         INTEGER NOT NULL REFERENCES episodes (id) ON DELETE CASCADE,
    curator         TEXT NOT NULL,
    -- The graphs file (core::episode::EpisodeGraphs as JSON), not yet checked.
    graphs          TEXT NOT NULL,
    updated_at_ms   INTEGER NOT NULL,
    PRIMARY KEY (episode, curator)
) WITHOUT ROWID;
