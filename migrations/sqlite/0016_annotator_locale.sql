-- The language an annotator chose with the pages' language switch ("en", "zh-CN"), or NULL
-- for none: then the browser's Accept-Language decides. Logging in sets the browser's language
-- cookie from it.
ALTER TABLE annotators ADD COLUMN locale TEXT;
