-- Who did what to what, and when: admin actions, tokens, submissions, visibility changes,
-- assignments, protocol runs, imports and annotation submits. Actors and targets are kept by
-- name, not by reference, so an entry outlives the account or dataset it mentions.
CREATE TABLE audit_log (
    id          INTEGER PRIMARY KEY,
    at          TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ', 'now')),
    -- 'account' (API token), 'annotator' (browser session), 'operator' (command line),
    -- 'server' (the service itself, e.g. loading the demo).
    actor_kind  TEXT NOT NULL CHECK (actor_kind IN ('account', 'annotator', 'operator', 'server')),
    actor       TEXT NOT NULL,
    action      TEXT NOT NULL,
    target      TEXT NOT NULL,
    -- The dataset the action concerns, when there is one (filtering, report bundles).
    dataset     TEXT,
    detail      TEXT NOT NULL DEFAULT ''
);

CREATE INDEX audit_log_by_dataset ON audit_log (dataset, id);
CREATE INDEX audit_log_by_action ON audit_log (action, id);
