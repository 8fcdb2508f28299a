"""Replicates a stored dataset's items in SQL until it holds TARGET items, for the benchmarks
that need a full-size (8,972-item) dataset: ids get a `_rN` suffix; frames, images and
signature tables are shared with the originals. Run with the server stopped.

    python3 scripts/lib/replicate_items.py DB DATASET TARGET
"""
import sqlite3
import sys

db, dataset, target = sys.argv[1], sys.argv[2], int(sys.argv[3])
con = sqlite3.connect(db)
con.execute("PRAGMA foreign_keys=ON")
(dataset_id,) = con.execute("SELECT id FROM datasets WHERE name = ?", (dataset,)).fetchone()
base = con.execute(
    "SELECT id, item_id FROM items WHERE dataset_id = ? ORDER BY id", (dataset_id,)
).fetchall()
n, copy = len(base), 1
while n < target:
    for row_id, item_id in base:
        if n >= target:
            break
        cur = con.execute(
            "INSERT INTO items (dataset_id, item_id, item_type, direction, step_length, task_name,"
            " key_frame_ids, question, actions, gt_answer, content_hash, source_line)"
            " SELECT dataset_id, ?, item_type, direction, step_length, task_name, key_frame_ids,"
            " question, actions, gt_answer, content_hash, source_line FROM items WHERE id = ?",
            (f"{item_id}_r{copy}", row_id),
        )
        new_row = cur.lastrowid
        con.execute(
            "INSERT INTO item_images (item, position, path, frame)"
            " SELECT ?, position, path, frame FROM item_images WHERE item = ?",
            (new_row, row_id),
        )
        con.execute(
            "INSERT INTO item_signatures (item, source, signatures)"
            " SELECT ?, source, signatures FROM item_signatures WHERE item = ?",
            (new_row, row_id),
        )
        n += 1
    copy += 1
con.execute("UPDATE content_generation SET value = value + 1")
con.commit()
print(f"dataset '{dataset}': {n} items", file=sys.stderr)
