-- Model runs: the hub asking an OpenAI-compatible chat-completions endpoint every item of a
-- dataset, one durable row per item, then submitting the answers as any submitter would.
-- No key is ever stored: the endpoint is kept without credentials, and a server-side run
-- names the environment variable holding its key.
CREATE TABLE model_runs (
    id              INTEGER PRIMARY KEY,
    -- Given with --run, or made from the run's identity (dataset, endpoint, model, params).
    name            TEXT NOT NULL UNIQUE,
    dataset         INTEGER NOT NULL REFERENCES datasets (id) ON DELETE CASCADE,
    -- scheme://host[:port]/path: never userinfo or a query string.
    endpoint        TEXT NOT NULL,
    model           TEXT NOT NULL,
    -- The generation parameters sent with every request (JSON: temperature, max_tokens).
    params          TEXT NOT NULL,
    prompt_version  TEXT NOT NULL,
    prompt_hash     TEXT NOT NULL,
    -- The API token (of the model-runs account) the submission is made with.
    token           INTEGER NOT NULL REFERENCES api_tokens (id) ON DELETE CASCADE,
    -- The submission the answers went into, and the stamp it was made with (JSON: endpoint
    -- host, model, parameters, prompt version and hash, hub version, usage and cost).
    submission      INTEGER REFERENCES submissions (id) ON DELETE SET NULL,
    stamp           TEXT,
    created_by      TEXT NOT NULL,
    created_at      TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);

CREATE INDEX model_runs_by_dataset ON model_runs (dataset);

-- One row per item asked, written when the item is done (answered, or failed for good):
-- an item with a row is never asked again, unless it failed and the run retries failures.
CREATE TABLE model_run_items (
    run                 INTEGER NOT NULL REFERENCES model_runs (id) ON DELETE CASCADE,
    item                INTEGER NOT NULL REFERENCES items (id) ON DELETE CASCADE,
    state               TEXT NOT NULL CHECK (state IN ('answered', 'failed')),
    -- The reply's text as the model wrote it (also kept for a cut reply); NULL when no reply.
    response            TEXT,
    finish_reason       TEXT,
    -- Summed over every call made for the item.
    prompt_tokens       INTEGER NOT NULL,
    completion_tokens   INTEGER NOT NULL,
    -- Of the last call.
    latency_ms          INTEGER NOT NULL,
    attempts            INTEGER NOT NULL,
    -- Why the item failed, or what the last failed call said before an answer came.
    error               TEXT,
    done_at             TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now')),
    PRIMARY KEY (run, item)
) WITHOUT ROWID;
