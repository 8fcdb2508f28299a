//! `enact-hub migrate-db`: a SQLite database in use (items, frames, a submission, an
//! annotator's answer, the audit log) copied into PostgreSQL answers every request as the
//! original did, and copies back to SQLite row for row. Runs in the suite's PostgreSQL pass.

use enact_hub::app::Hub;
use enact_hub::core::credentials::Role;
use enact_hub::store::{self, Pool};
use enact_hub::web::WebConfig;
use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::annotate::{Browser, PASSWORD, annotator_on, assign_on};
use crate::helpers::*;

/// The JSON of `path` on `server`, read with `token`.
async fn read(server: &TestServer, path: &str, token: &str) -> Value {
    let r = server
        .client
        .get(server.url(path))
        .bearer_auth(token)
        .send()
        .await
        .expect("GET");
    assert_eq!(r.status(), StatusCode::OK, "{path}");
    r.json().await.expect("json")
}

fn migrate(from: &std::path::Path, to: &std::path::Path) -> String {
    let out = enact_hub()
        .arg("migrate-db")
        .arg("--from")
        .arg(from)
        .arg("--to")
        .arg(to)
        .output()
        .expect("run migrate-db");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    stderr
}

/// Every table's row count.
async fn counts(pool: &Pool) -> Vec<(String, i64)> {
    let mut conn = pool.acquire().await.expect("conn");
    let mut all = Vec::new();
    for table in store::copy::TABLES {
        all.push((
            table.name.to_owned(),
            table.count(&mut conn).await.expect("count"),
        ));
    }
    all
}

/// Every table of the schema with its columns, as the database itself lists them.
async fn schema(pool: &Pool) -> std::collections::BTreeMap<String, Vec<String>> {
    let rows: Vec<(String, String)> = match pool {
        Pool::Sqlite(p) => sqlx::query_as(
            "SELECT t.name, c.name FROM sqlite_master t, pragma_table_info(t.name) c \
             WHERE t.type = 'table' AND t.name NOT LIKE 'sqlite_%'",
        )
        .fetch_all(p)
        .await
        .expect("sqlite schema"),
        Pool::Pg(p) => sqlx::query_as(
            "SELECT table_name::text, column_name::text FROM information_schema.columns \
             WHERE table_schema = current_schema()",
        )
        .fetch_all(p)
        .await
        .expect("postgres schema"),
    };
    let mut tables = std::collections::BTreeMap::<String, Vec<String>>::new();
    for (table, column) in rows {
        if table != "_sqlx_migrations" {
            tables.entry(table).or_default().push(column);
        }
    }
    for columns in tables.values_mut() {
        columns.sort();
    }
    tables
}

#[tokio::test]
async fn the_copy_knows_every_table_and_column_of_the_schema() {
    // A table or column a migration adds and the copy does not list would be silently left
    // behind by migrate-db and by backups of PostgreSQL.
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let copied: std::collections::BTreeMap<String, Vec<String>> = store::copy::TABLES
        .iter()
        .map(|t| {
            let mut columns: Vec<String> = t.columns().map(str::to_owned).collect();
            columns.sort();
            (t.name.to_owned(), columns)
        })
        .collect();
    assert_eq!(schema(&pool).await, copied);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sqlite_database_in_use_moves_to_postgres_and_back_unchanged() {
    let Some(postgres) = postgres_server() else {
        eprintln!("no PostgreSQL server (ENACT_HUB_TEST_POSTGRES unset): skipping");
        return;
    };
    // The SQLite database, used through its server.
    let dir = tempfile::tempdir().expect("tempdir");
    let sqlite_path = dir.path().join("hub.db");
    let sqlite = Pool::Sqlite(store::open(&sqlite_path).await.expect("open"));
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    import(&sqlite, &root, &options("mini")).await;
    let (_, token) = api_token(&sqlite, "team", Role::Admin, None, None).await;
    let alice = annotator_on(&sqlite, "alice", false).await;
    let first = records[0]["id"].as_str().expect("id");
    assign_on(&sqlite, "mini", alice, &[first]).await;
    let original = serve_hub(
        Hub::from(sqlite.clone()),
        sqlite.clone(),
        tempfile::tempdir().expect("tempdir"),
        &WebConfig::default(),
    )
    .await;
    let r = original
        .client
        .post(original.url("/api/v1/datasets/mini/submissions?model=m"))
        .bearer_auth(&token)
        .body(answers(&records, &[1]))
        .send()
        .await
        .expect("submit");
    assert_eq!(r.status(), StatusCode::CREATED);
    let submission: Value = r.json().await.expect("json");
    let mut browser = Browser::new(&original);
    browser.login("alice", PASSWORD).await;
    let csrf = browser.csrf("/annotate").await;
    browser.get(&format!("/annotate/mini/{first}")).await;
    let counts_json = json!({"placements": 2, "swaps": 0, "clears": 0, "undos": 0});
    let r = browser
        .post_json(
            &format!("/annotate/mini/{first}/submit"),
            Some(&csrf),
            &json!({"slots": [2, 1], "counts": counts_json}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let paths = [
        "/api/v1/datasets/mini/leaderboard".to_owned(),
        format!("/api/v1/datasets/mini/items/{first}"),
        format!("/api/v1/submissions/{}", submission["id"]),
        "/api/v1/datasets".to_owned(),
    ];
    let mut before = Vec::new();
    for path in &paths {
        before.push(read(&original, path, &token).await);
    }
    let before_counts = counts(&sqlite).await;
    original.stop().await;

    // Into PostgreSQL: the same answers, the same rows; a second run is refused.
    let url = std::path::PathBuf::from(new_postgres_database(&postgres).await);
    let report = migrate(&sqlite_path, &url);
    assert!(report.contains("copied "), "{report}");
    let out = enact_hub()
        .arg("migrate-db")
        .arg("--from")
        .arg(&sqlite_path)
        .arg("--to")
        .arg(&url)
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("rows of datasets: a whole database is only copied into an empty one"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pg = Pool::Pg(
        store::db::open_postgres(url.to_str().expect("utf-8"), 4)
            .await
            .expect("open"),
    );
    assert_eq!(counts(&pg).await, before_counts);
    let moved = serve_hub(
        Hub::from(pg.clone()),
        pg.clone(),
        tempfile::tempdir().expect("tempdir"),
        &WebConfig::default(),
    )
    .await;
    for (path, expected) in paths.iter().zip(&before) {
        assert_eq!(&read(&moved, path, &token).await, expected, "{path}");
    }
    // The frames came along, and new rows get new ids.
    let frame = before[1]["images"][0]["url"].as_str().expect("frame url");
    assert_eq!(moved.get(frame).await.status(), StatusCode::OK);
    let r = moved
        .client
        .post(moved.url("/api/v1/datasets/mini/submissions?model=m2"))
        .bearer_auth(&token)
        .body(answers(&records, &[]))
        .send()
        .await
        .expect("submit");
    assert_eq!(r.status(), StatusCode::CREATED);
    let next: Value = r.json().await.expect("json");
    assert!(next["id"].as_i64() > submission["id"].as_i64(), "{next}");
    moved.stop().await;

    // And back into a new SQLite file, row for row.
    let back = dir.path().join("back.db");
    migrate(&url, &back);
    let copy = Pool::Sqlite(store::open(&back).await.expect("open"));
    assert_eq!(counts(&copy).await, counts(&pg).await);
}
