-- A submission's error analysis (core::error_analysis), computed on first request and kept:
-- scores and answers never change after submission. The JSON carries its own version; a row
-- written by an older analysis is recomputed.
ALTER TABLE submissions ADD COLUMN error_analysis TEXT;
