-- A submission's verdicts are read and deleted by submission (the key's first column). The
-- index by item that 0015 added, for the cascade when an import replaces items, cost every
-- submission one scattered page write per item: a full-size submission held the write lock
-- for about 330 ms instead of about 60 ms, and annotators waited behind it. The verdicts no
-- longer reference items, so nothing needs that index: a replacing import's cut-over deletes
-- the replaced items' verdicts itself, by key (store::staged::publish_into).
CREATE TABLE submission_items_by_key (
    submission          INTEGER NOT NULL REFERENCES submissions (id) ON DELETE CASCADE,
    -- The items row judged (items.id); deleted with it by the code that deletes items.
    item                INTEGER NOT NULL,
    -- Line (or array element) of the body the answer came from; NULL when missing.
    line                INTEGER,
    raw_answer          TEXT,    -- the `answer` value as JSON, as submitted
    permutation         TEXT,    -- JSON list, when the answer could be read
    outcome             TEXT NOT NULL CHECK (outcome IN ('scored', 'unparseable', 'missing')),
    failure             TEXT,    -- why the answer could not be read
    exact_match         INTEGER NOT NULL,
    semantic_match      INTEGER NOT NULL,
    task_accuracy       INTEGER NOT NULL,
    pairwise_accuracy   REAL,
    PRIMARY KEY (submission, item)
) WITHOUT ROWID;

INSERT INTO submission_items_by_key
    SELECT submission, item, line, raw_answer, permutation, outcome, failure, exact_match,
           semantic_match, task_accuracy, pairwise_accuracy
    FROM submission_items;
DROP TABLE submission_items;
ALTER TABLE submission_items_by_key RENAME TO submission_items;
