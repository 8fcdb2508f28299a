-- As SQLite's 0025, so that both databases keep the same tables. PostgreSQL announces changes
-- with NOTIFY instead, so this table stays empty there.
CREATE TABLE change_feed (
    id BIGSERIAL PRIMARY KEY,
    origin TEXT NOT NULL,
    payload TEXT NOT NULL
);
