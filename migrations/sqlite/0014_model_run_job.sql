-- The job a run was last started on the server with (NULL for a run only ever worked by the
-- CLI), so a run's page finds its job directly instead of reading every job's payload.
ALTER TABLE model_runs ADD COLUMN job INTEGER REFERENCES jobs (id) ON DELETE SET NULL;

-- Runs started before this column: their newest model-run job, found by its payload's run_id.
UPDATE model_runs SET job = (
    SELECT max(j.id) FROM jobs j
    WHERE j.kind = 'model_run' AND json_extract(j.payload, '$.run_id') = model_runs.id
);
