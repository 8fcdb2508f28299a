-- A replacing import's cut-over deletes the replaced items but leaves their verdicts: at full size
-- (hundreds of submissions of thousands of items) deleting those in the cut-over's transaction
-- would hold the write lock for seconds. Verdicts do not reference items, so they simply name
-- no item any more; every reader joins or maps them to the dataset's items and passes over them.
-- This row says a dataset has such verdicts left: they are deleted afterwards, one submission
-- per short transaction, in id order. `swept_through` is the last submission done; a newer
-- cut-over bumps `generation` and starts again from the beginning, and a sweeper of an older
-- generation then stops writing its progress.
CREATE TABLE verdict_sweeps (
    dataset       INTEGER PRIMARY KEY REFERENCES datasets (id) ON DELETE CASCADE,
    generation    INTEGER NOT NULL DEFAULT 1,
    swept_through INTEGER NOT NULL DEFAULT 0
);
