-- The enact-hub build that computed a submission's scores ("0.1.0+<commit>"): set when it is
-- scored and again when it is rescored. Empty for submissions scored before this column.
ALTER TABLE submissions ADD COLUMN scored_by TEXT NOT NULL DEFAULT '';
