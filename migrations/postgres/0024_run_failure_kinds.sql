-- Why a failed item of a model run has no answer, as a kind the code reads (see the SQLite
-- migration 0032): NULL for an answered item; older failed rows get the kind their words name.
ALTER TABLE model_run_items ADD COLUMN failure TEXT;

UPDATE model_run_items SET failure = CASE
    WHEN error = 'empty response' THEN 'empty'
    WHEN error LIKE 'response cut off%' THEN 'cut'
    WHEN error ~ '^gave up after [0-9]+ rate-limited calls: ' THEN 'rate_limited'
    WHEN error ~ '^(gave up after [0-9]+ attempts: )?HTTP 2' THEN 'unreadable'
    WHEN error ~ '^(gave up after [0-9]+ attempts: )?HTTP [0-9]{3}:'
        THEN 'http_' || substring(error from 'HTTP ([0-9]{3}):')
    WHEN error ~ '^gave up after [0-9]+ attempts: ' THEN 'no_reply'
    ELSE 'unrecorded'
END
WHERE state = 'failed';
