-- The job a run was last started on the server with (see migrations/sqlite/0014_model_run_job.sql).
ALTER TABLE model_runs ADD COLUMN job BIGINT REFERENCES jobs (id) ON DELETE SET NULL;

-- Runs started before this column: their newest model-run job, found by its payload's run_id.
UPDATE model_runs SET job = (
    SELECT max(j.id) FROM jobs j
    WHERE j.kind = 'model_run' AND (j.payload::json ->> 'run_id')::bigint = model_runs.id
);
