-- Per-item transition signatures, for semantic matching (see src/semantics.rs). An item
-- without a row here is scored by exact match only.
CREATE TABLE item_signatures (
    item        INTEGER PRIMARY KEY REFERENCES items (id) ON DELETE CASCADE,
    source      TEXT NOT NULL CHECK (source IN ('scene_graph', 'action_text')),
    -- The serialised ItemSignatures table (verifier::ItemSignatures).
    signatures  TEXT NOT NULL
);
