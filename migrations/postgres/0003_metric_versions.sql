-- Human verdicts stored when an answer is finished, and the metric version of every stored
-- result (core::metric::METRIC_VERSION): a result of an older version is marked on leaderboards
-- until `enact-hub rescore` computes it again. SQLite's 0011.

-- A submission's scores, per-item verdicts and kept error analysis are computed together, so
-- they carry one version. Rows stored before versions were recorded are version 1.
ALTER TABLE submissions ADD COLUMN metric_version BIGINT NOT NULL DEFAULT 1;

-- An answered item's verdict, as a submission line's: NULL (all five) for skips and flags, and
-- for answers finished before this migration until they are rescored (the Human row computes
-- those on the fly meanwhile).
ALTER TABLE annotations ADD COLUMN exact_match BOOLEAN;
ALTER TABLE annotations ADD COLUMN semantic_match BOOLEAN;
ALTER TABLE annotations ADD COLUMN task_accuracy BOOLEAN;
ALTER TABLE annotations ADD COLUMN pairwise_accuracy DOUBLE PRECISION;
ALTER TABLE annotations ADD COLUMN metric_version BIGINT;

-- What a rescore looks for: a dataset's results below the current version.
CREATE INDEX submissions_by_metric_version ON submissions (dataset, metric_version);
