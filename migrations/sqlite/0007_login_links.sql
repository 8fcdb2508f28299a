-- Single-use login links: following one starts a session for its annotator without a password
-- (`serve --demo` prints one for the demo admin). Only the SHA-256 of the secret is stored.
CREATE TABLE login_links (
    hash       TEXT PRIMARY KEY,
    annotator  INTEGER NOT NULL REFERENCES annotators (id) ON DELETE CASCADE,
    created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%SZ', 'now'))
);
