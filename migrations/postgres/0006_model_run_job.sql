-- The job a run was last started on the server with (see migrations/sqlite/0014_model_run_job.sql).
ALTER TABLE model_runs ADD COLUMN job BIGINT REFERENCES jobs (id) ON DELETE SET NULL;
