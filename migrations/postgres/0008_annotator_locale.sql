-- The language an annotator chose (see migrations/sqlite/0016_annotator_locale.sql).
ALTER TABLE annotators ADD COLUMN locale TEXT;
