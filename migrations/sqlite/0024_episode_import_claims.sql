-- One import of an episode name at a time. An incomplete episode is its import's claim on the
-- name: the import renews `import_alive_until_ms` (milliseconds since the Unix epoch) with
-- every batch of frames it writes. Another import of the same name is refused while that
-- time is ahead, and takes the name over (removing the incomplete episode) once it has
-- passed, because the import holding it was killed or stalled. Incomplete episodes left
-- before this column existed have none, so the next import takes them over at once.
ALTER TABLE episodes ADD COLUMN import_alive_until_ms INTEGER;
