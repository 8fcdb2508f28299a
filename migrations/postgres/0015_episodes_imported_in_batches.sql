-- As SQLite's 0023: an episode imported a few frames per transaction is complete only once
-- its last frame is written.
ALTER TABLE episodes ADD COLUMN complete INTEGER NOT NULL DEFAULT 1 CHECK (complete IN (0, 1));
