-- The item list (`GET /api/v1/datasets/{dataset}/items` and its page) counts the items its
-- filter matches and reads one page in import order. Through items_by_task it read every
-- item's whole row (about 3 KB each) to test the filter: about 18 ms for 8,972 items, most of a
-- core under the mixed load's ten readers. This index holds everything the list reads, in
-- import order (0.6 ms).
CREATE INDEX items_listing ON items (dataset_id, id, direction, step_length, task_name, item_type, item_id);
