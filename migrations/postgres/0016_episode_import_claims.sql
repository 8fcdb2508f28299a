-- As SQLite's 0024: an incomplete episode is its import's claim on the name, alive until
-- `import_alive_until_ms` (milliseconds since the Unix epoch), which the import renews with
-- every batch of frames; past it, the next import of the name takes the name over.
ALTER TABLE episodes ADD COLUMN import_alive_until_ms BIGINT;
