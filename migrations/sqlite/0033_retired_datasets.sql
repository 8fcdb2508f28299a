-- A replacing import's cut-over that replaces most of a dataset does not move its rows: the
-- staged version's hidden `datasets` row becomes the dataset (name, settings, submissions, runs
-- and everything else that names the dataset are pointed at it), and the old row is retired
-- under a hidden name. Its items (the replaced ones, with their images and signatures) are then
-- deleted a few hundred per short transaction, and the row last. This is the list of retired
-- rows still to delete, with the name their dataset had: anything written to a retired row
-- after its cut-over (a write that resolved the dataset just before) is pointed at the dataset
-- of that name before the row goes, rather than deleted with it.
CREATE TABLE retired_datasets (
    dataset     INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    name        TEXT NOT NULL,
    retired_at  TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);
