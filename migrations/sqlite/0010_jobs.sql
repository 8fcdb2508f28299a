-- Long work that must survive restarts and be worked by one instance at a time: model runs,
-- rescoring (and later staged imports). A job is enqueued in the transaction of the change
-- that asks for it; an instance claims the next one by taking its lease (an owner and a time,
-- in milliseconds since the epoch, renewed while it works) and another instance takes it over
-- once the lease has run out. The code of a job is resumable, so starting it again from the
-- top after a crash or a takeover only finishes what is left.
CREATE TABLE jobs (
    id              INTEGER PRIMARY KEY,
    -- Which code works it ('model_run', 'rescore'); checked by the application, so that a new
    -- kind needs no migration.
    kind            TEXT NOT NULL,
    -- What the job's code reads (JSON), never a secret.
    payload         TEXT NOT NULL,
    state           TEXT NOT NULL DEFAULT 'queued'
                    CHECK (state IN ('queued', 'running', 'paused', 'done', 'failed', 'cancelled')),
    -- A small JSON value the job's code writes as it goes, for pages and the API.
    progress        TEXT,
    -- Times it was started (claimed); failures wait 1 min × 2^(attempts − 1) before the next.
    attempts        INTEGER NOT NULL DEFAULT 0,
    last_error      TEXT,
    -- Not claimed before this time (ms since the epoch).
    run_after_ms    INTEGER NOT NULL DEFAULT 0,
    lease_owner     TEXT,
    lease_until_ms  INTEGER,
    created_by      TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    updated_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    finished_at     TEXT
);

CREATE INDEX jobs_claimable ON jobs (state, run_after_ms, id);
CREATE INDEX jobs_by_kind ON jobs (kind, id);
