-- The job a run was last started on the server with (NULL for a run only ever worked by the
-- CLI), so a run's page finds its job directly instead of reading every job's payload.
ALTER TABLE model_runs ADD COLUMN job INTEGER REFERENCES jobs (id) ON DELETE SET NULL;
