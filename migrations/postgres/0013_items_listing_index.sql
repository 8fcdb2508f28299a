-- As SQLite's 0021: everything the item list reads, in import order, so counting and paging
-- it does not read whole item rows.
CREATE INDEX items_listing ON items (dataset_id, id, direction, step_length, task_name, item_type, item_id);
