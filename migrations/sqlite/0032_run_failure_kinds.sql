-- Why a failed item of a model run has no answer, as a kind the code reads (core::model_run::
-- RunFailure's code): no_reply, http_NNN, rate_limited, unreadable, empty, cut. NULL for an
-- answered item. `error` keeps the words. Rows failed before this migration get the kind their
-- words name, in the forms the hub has always written them; any other is `unrecorded`.
ALTER TABLE model_run_items ADD COLUMN failure TEXT;

UPDATE model_run_items SET failure = CASE
    WHEN error = 'empty response' THEN 'empty'
    WHEN error LIKE 'response cut off%' THEN 'cut'
    WHEN error GLOB 'gave up after * rate-limited calls: *' THEN 'rate_limited'
    -- A reply with a success status that is not a chat completion: "HTTP 200 OK: …".
    WHEN error GLOB 'HTTP 2*' OR error GLOB 'gave up after * attempts: HTTP 2*' THEN 'unreadable'
    WHEN error GLOB 'HTTP [0-9][0-9][0-9]:*' THEN 'http_' || substr(error, 6, 3)
    WHEN error GLOB 'gave up after * attempts: HTTP [0-9][0-9][0-9]:*'
        THEN 'http_' || substr(error, instr(error, ': HTTP ') + 7, 3)
    -- A timeout or a connection that failed: "timed out", "cannot connect: …", "request failed: …".
    WHEN error GLOB 'gave up after * attempts: *' THEN 'no_reply'
    ELSE 'unrecorded'
END
WHERE state = 'failed';
