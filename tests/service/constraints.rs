//! Refused writes recognised by the database's error code and constraint name, never its
//! message, on whichever database the suite runs against; and the use cases' answers when a
//! duplicate gets past their own checks (a twin request racing its first).

use enact_hub::app::refusal::Refusal;
use enact_hub::app::{self, AppError, Hub};
use enact_hub::core::agreement::protocol::ProtocolPlan;
use enact_hub::core::credentials::{Role, Scope, random_token, token_hash};
use enact_hub::core::submission::{Provenance, SubmissionMetadata};
use enact_hub::store;
use enact_hub::store::Pool;
use enact_hub::store::db::{UniqueKey, Violation, ViolationKind, violation};
use enact_hub::store::submissions::NewSubmission;

use crate::helpers::*;

/// On PostgreSQL the violation names its constraint; SQLite names none.
fn assert_named(e: &sqlx::Error, kind: ViolationKind, constraint: &str) {
    let expected = Violation {
        kind,
        constraint: (!on_sqlite()).then(|| constraint.to_owned()),
    };
    assert_eq!(violation(e), Some(expected), "{e}");
}

#[tokio::test]
async fn a_reused_idempotency_key_is_recognised_by_its_constraint() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let reply = server
        .call(
            reqwest::Method::POST,
            "/api/v1/datasets/mini/submissions?model=m",
        )
        .bearer(&token)
        .header("Idempotency-Key", "k-1")
        .body(ground_truth_answers(&records))
        .send()
        .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let mut conn = server.pool.acquire().await.expect("conn");
    let first = store::submissions::by_id(&mut conn, reply.id())
        .await
        .expect("read")
        .expect("stored");
    let token_id: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT token FROM submissions WHERE id = $1").bind(first.id)
    )
    .expect("token");
    let metadata = SubmissionMetadata {
        model: "m".to_owned(),
        ..SubmissionMetadata::default()
    };
    let again = NewSubmission {
        dataset: first.dataset_id,
        account: first.account_id,
        token: token_id,
        idempotency_key: Some("k-1"),
        body_sha256: &first.body_sha256,
        metadata: &metadata,
        scores: &first.scores,
        metric_version: enact_hub::core::metric::METRIC_VERSION,
        scored_by: enact_hub::core::version::BUILD,
        provenance: Provenance::Submitted,
    };
    drop(conn);
    let e = store::submissions::insert(&mut write_tx(&server.pool).await, &again)
        .await
        .expect_err("the key is taken");
    assert_named(&e, ViolationKind::Unique, "submissions_idempotency_key");
    assert!(UniqueKey::SUBMISSION_IDEMPOTENCY_KEY.is_violated_by(&e));
    if !on_sqlite() {
        // The name tells the keys apart where the database gives one.
        assert!(!UniqueKey::ANNOTATOR_NAME.is_violated_by(&e));
    }
    // Another key is no violation at all.
    let other = NewSubmission {
        idempotency_key: Some("k-2"),
        ..again
    };
    let mut tx = write_tx(&server.pool).await;
    store::submissions::insert(&mut tx, &other)
        .await
        .expect("a new key is stored");
    tx.commit().await.expect("commit");
}

#[tokio::test]
async fn a_taken_name_is_recognised_by_its_constraint() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let hash = || token_hash(&random_token());
    let mut tx = write_tx(&pool).await;
    store::annotations::create_annotator(&mut tx, "ada", false, &hash())
        .await
        .expect("a new name");
    tx.commit().await.expect("commit");
    let e = store::annotations::create_annotator(&mut write_tx(&pool).await, "ada", true, &hash())
        .await
        .expect_err("the name is taken");
    assert_named(&e, ViolationKind::Unique, "annotators_name_key");
    assert!(UniqueKey::ANNOTATOR_NAME.is_violated_by(&e));
    if !on_sqlite() {
        assert!(!UniqueKey::STUDY_NAME.is_violated_by(&e));
    }

    // The use case turns it into the refusal both adapters show.
    let hub = Hub::from(pool);
    let refused = app::annotators::create(&hub, &tester(), "ada", false).await;
    let Err(AppError::Conflict(message)) = refused else {
        panic!("a taken name is a conflict: {refused:?}");
    };
    assert_eq!(message, "an annotator named 'ada' already exists");
}

#[tokio::test]
async fn a_missing_referenced_row_is_recognised_as_a_foreign_key_violation() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let e = store::annotations::assign(&mut write_tx(&pool).await, &[(4242, 4243)])
        .await
        .expect_err("neither the annotator nor the item exists");
    let found = violation(&e).expect("a constraint violation");
    assert_eq!(found.kind, ViolationKind::ForeignKey, "{e}");
    if !on_sqlite() {
        assert!(
            found
                .constraint
                .is_some_and(|c| c.starts_with("assignments_"))
        );
    }
    for key in UniqueKey::ALL {
        assert!(!key.is_violated_by(&e), "{key:?}");
    }
    // Not a constraint at all.
    assert_eq!(violation(&sqlx::Error::RowNotFound), None);
}

/// Unique keys (primary keys included) of `table`, each as its sorted columns.
async fn unique_keys(pool: &Pool, table: &str) -> Vec<Vec<String>> {
    let mut keys: Vec<Vec<String>> = match pool {
        Pool::Sqlite(p) => {
            // An INTEGER PRIMARY KEY is the rowid and has no index: read it from table_info.
            let mut keys = Vec::new();
            let pk: Vec<String> = sqlx::query_scalar(
                "SELECT name FROM pragma_table_info($1) WHERE pk > 0 ORDER BY name",
            )
            .bind(table)
            .fetch_all(p)
            .await
            .expect("table_info");
            if !pk.is_empty() {
                keys.push(pk);
            }
            let indexes: Vec<String> = sqlx::query_scalar(
                "SELECT name FROM pragma_index_list($1) WHERE \"unique\" = 1 AND origin <> 'pk'",
            )
            .bind(table)
            .fetch_all(p)
            .await
            .expect("index_list");
            for index in indexes {
                let columns: Vec<String> =
                    sqlx::query_scalar("SELECT name FROM pragma_index_info($1) ORDER BY name")
                        .bind(&index)
                        .fetch_all(p)
                        .await
                        .expect("index_info");
                keys.push(columns);
            }
            keys
        }
        Pool::Pg(p) => {
            let rows: Vec<String> = sqlx::query_scalar(
                "SELECT string_agg(a.attname, ',' ORDER BY a.attname) FROM pg_index x \
                 JOIN pg_class t ON t.oid = x.indrelid \
                 JOIN pg_attribute a ON a.attrelid = t.oid AND a.attnum = ANY(x.indkey) \
                 WHERE t.relname = $1 AND x.indisunique GROUP BY x.indexrelid",
            )
            .bind(table)
            .fetch_all(p)
            .await
            .expect("pg_index");
            rows.iter()
                .map(|r| r.split(',').map(str::to_owned).collect())
                .collect()
        }
    };
    keys.sort();
    keys
}

#[tokio::test]
async fn unique_keys_are_the_only_ones_on_their_tables() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    // SQLite reports no constraint name, so `UniqueKey::is_violated_by` takes any unique
    // violation on these tables for the key: that holds only while each has no other unique
    // key an INSERT can collide with (generated ids and hashes of random bytes cannot).
    let expected: [(&str, &[&[&str]]); 6] = [
        ("submissions", &[&["id"], &["idempotency_key", "token"]]),
        ("annotators", &[&["id"], &["invite_hash"], &["name"]]),
        ("studies", &[&["id"], &["name"]]),
        ("agreement_rounds", &[&["dataset"]]),
        ("episodes", &[&["id"], &["name"]]),
        (
            "reported_results",
            &[&["dataset", "model", "source"], &["id"]],
        ),
    ];
    for key in UniqueKey::ALL {
        assert!(
            expected.iter().any(|(table, _)| *table == key.table),
            "{key:?} is not checked here"
        );
    }
    for (table, keys) in expected {
        let want: Vec<Vec<String>> = keys
            .iter()
            .map(|k| k.iter().map(|c| (*c).to_owned()).collect())
            .collect();
        assert_eq!(unique_keys(&pool, table).await, want, "{table}");
    }
    // PostgreSQL names each key as `UniqueKey` says.
    if let Pool::Pg(p) = &pool {
        for key in UniqueKey::ALL {
            let found: Option<String> = sqlx::query_scalar(
                "SELECT c.conname::text FROM pg_constraint c JOIN pg_class t ON t.oid = c.conrelid \
                 WHERE t.relname = $1 AND c.conname = $2",
            )
            .bind(key.table)
            .bind(key.constraint)
            .fetch_optional(p)
            .await
            .expect("pg_constraint");
            assert!(found.is_some(), "{key:?}");
        }
    }
}

#[tokio::test]
async fn a_twin_request_that_stores_first_is_answered_as_a_repeat() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let hub = Hub::from(server.pool.clone());
    let caller = app::tokens::authorize(&hub, &token, Scope::Submit)
        .await
        .expect("caller");
    let metadata = || SubmissionMetadata {
        model: "m".to_owned(),
        ..SubmissionMetadata::default()
    };
    let body = ground_truth_answers(&records).into_bytes();
    // The body is read after the key was looked up and found unused: a twin with the same key
    // stores its submission in between, as a concurrent request would.
    let same = app::submissions::submit(
        &hub,
        &caller,
        "mini",
        metadata(),
        Provenance::Submitted,
        Some("k"),
        async {
            twin_with_key(&hub, &caller, "k", body.clone()).await;
            Ok(body.clone())
        },
    )
    .await
    .expect("answered");
    let app::submissions::Submitted::Repeated(row) = same else {
        panic!("the second of two twins is a repeat: {same:?}");
    };
    let stored: i64 = count(&server.pool, "SELECT min(id) FROM submissions").await;
    assert_eq!(row.id, stored);
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        1
    );

    // The same race with another body is the conflict a late request with it gets.
    let other = answers(&records, &[0]).into_bytes();
    let raced = app::submissions::submit(
        &hub,
        &caller,
        "mini",
        metadata(),
        Provenance::Submitted,
        Some("k2"),
        async {
            twin_with_key(&hub, &caller, "k2", body.clone()).await;
            Ok(other)
        },
    )
    .await;
    let Err(AppError::Refused(refusal @ Refusal::IdempotencyKeyReused { .. })) = raced else {
        panic!("a different body under a used key is a conflict: {raced:?}");
    };
    let message = refusal.to_string();
    assert!(message.contains("with a different body"), "{message}");
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM submissions").await,
        2
    );
}

async fn twin_with_key(hub: &Hub, caller: &app::tokens::Caller, key: &str, body: Vec<u8>) {
    let metadata = SubmissionMetadata {
        model: "m".to_owned(),
        ..SubmissionMetadata::default()
    };
    app::submissions::submit(
        hub,
        caller,
        "mini",
        metadata,
        Provenance::Submitted,
        Some(key),
        async { Ok(body) },
    )
    .await
    .expect("the twin is stored");
}

#[tokio::test]
async fn a_second_protocol_round_is_recognised_by_the_round_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    db!(
        pool,
        execute,
        sqlx::query("INSERT INTO datasets (name) VALUES ('d')")
    )
    .expect("a dataset");
    let dataset: i64 = db!(
        pool,
        fetch_one,
        sqlx::query_scalar("SELECT id FROM datasets WHERE name = 'd'")
    )
    .expect("its id");
    let plan = ProtocolPlan {
        items_per_cell: 1,
        seed: 7,
        samples: Vec::new(),
        assignments: Vec::new(),
        shortfalls: Vec::new(),
    };
    let mut tx = write_tx(&pool).await;
    store::agreement::insert_round(&mut tx, dataset, &plan, None)
        .await
        .expect("the first round");
    tx.commit().await.expect("commit");
    let e = store::agreement::insert_round(&mut write_tx(&pool).await, dataset, &plan, None)
        .await
        .expect_err("one round per dataset");
    assert_named(&e, ViolationKind::Unique, "agreement_rounds_pkey");
    assert!(UniqueKey::AGREEMENT_ROUND.is_violated_by(&e));
}
