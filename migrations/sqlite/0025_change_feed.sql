-- What each process announced to the others on this database (a leaderboard changed, an
-- annotator's standing on an item, a login session ended), written in the transaction that
-- makes the change. Running servers read the rows other processes wrote (the command line
-- excluding an annotator, setting gold items, rescoring) and drop what they cached. Only the
-- newest few thousand rows are kept: a server reads them twice a second.
CREATE TABLE change_feed (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    -- The announcing process (a random name each Hub takes when it opens the database).
    origin TEXT NOT NULL,
    -- `Change::payload`: `boards`, `standing 3 17`, `session <hash>`.
    payload TEXT NOT NULL
);
