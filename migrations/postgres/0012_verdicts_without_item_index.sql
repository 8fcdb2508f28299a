-- As SQLite's 0020: a submission's verdicts no longer reference items, so no index by item
-- is kept up on every submission; a replacing import's cut-over deletes the replaced items'
-- verdicts itself, by key (store::staged::publish_into).
ALTER TABLE submission_items DROP CONSTRAINT submission_items_item_fkey;
DROP INDEX submission_items_by_item;
