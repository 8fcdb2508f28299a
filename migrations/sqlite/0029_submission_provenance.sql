-- Where a submission's answers came from: `run` when this hub asked the model itself (a
-- model run filed it), `submitted` when they were uploaded. Set when the submission is
-- stored and never changed.
ALTER TABLE submissions ADD COLUMN provenance TEXT NOT NULL DEFAULT 'submitted'
    CHECK (provenance IN ('run', 'submitted'));

-- Runs' submissions stored before the column.
UPDATE submissions SET provenance = 'run'
WHERE id IN (SELECT submission FROM model_runs WHERE submission IS NOT NULL);

-- A row's run is found from its submission (the leaderboard links to the run's stamp).
CREATE INDEX model_runs_by_submission ON model_runs (submission);

-- Items are matched by content across datasets (a hidden dataset's items also in a public one).
CREATE INDEX items_by_content ON items (content_hash);
