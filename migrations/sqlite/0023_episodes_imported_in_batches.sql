-- An episode is imported a few frames per transaction, so that a long recording never holds
-- the write lock for long; until its last frame is written it is not complete, and no page,
-- list or export shows it. A killed import leaves an incomplete episode, removed by the next
-- import of the same name.
ALTER TABLE episodes ADD COLUMN complete INTEGER NOT NULL DEFAULT 1 CHECK (complete IN (0, 1));
