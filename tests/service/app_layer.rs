//! What the application layer promises both adapters: one naming rule for the web and the
//! command line, stored scores read back typed (and never read as zero when unreadable), and
//! every refusal of a JSON route as the JSON error body.

use enact_hub::app::refusal::Refusal;
use enact_hub::app::{self, AppError, Hub};
use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

/// Posts the ground truth of every record (so TA is 1) and returns the new submission's id.
async fn submit_ground_truth(server: &TestServer, token: &str, records: &[Value]) -> i64 {
    let reply = submit_to(
        server,
        "mini",
        "model=oracle",
        token,
        ground_truth_answers(records),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    reply.id()
}

#[tokio::test]
async fn stored_scores_come_back_typed_and_an_unreadable_one_names_its_submission() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let id = submit_ground_truth(&server, &token, &records).await;

    let hub = Hub::from(server.pool.clone());
    let (_, rows) = app::leaderboard::of(&hub, "mini")
        .await
        .expect("leaderboard");
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0].submission, Some(id));
    assert_eq!(rows[0].overall.task_accuracy, Some(1.0));
    assert_eq!(rows[0].overall.count, records.len());

    // A score this version cannot read is an error about that submission, not a row of zeros.
    db!(
        server.pool,
        execute,
        sqlx::query("UPDATE submissions SET scores = '{\"report\": {}}' WHERE id = $1").bind(id)
    )
    .expect("corrupt the stored scores");
    let Err(AppError::Internal(e)) = app::leaderboard::of(&hub, "mini").await else {
        panic!("an unreadable score must fail the leaderboard");
    };
    let message = format!("{e:#}");
    assert!(message.contains(&format!("submission {id}")), "{message}");
    assert!(message.contains("scores"), "{message}");
    let response = server.get("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(response.status(), 500);
    let body: Value = response.json().await.expect("json error");
    assert_eq!(body["error"], "internal error", "details stay in the log");
}

#[tokio::test]
async fn json_routes_refuse_bad_bodies_with_the_json_error_body() {
    let (server, _) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    for (body, content_type, status, says) in [
        ("{not json", "application/json", 400, "not valid JSON"),
        ("{\"name\": 7}", "application/json", 422, "does not fit"),
        (
            "{\"name\": \"a\", \"colour\": 1}",
            "application/json",
            422,
            "colour",
        ),
        (
            "name=a",
            "application/x-www-form-urlencoded",
            415,
            "application/json",
        ),
    ] {
        let reply = server
            .call(Method::POST, "/api/v1/admin/tokens")
            .bearer(&admin)
            .header("content-type", content_type)
            .body(body)
            .expect(status)
            .await;
        assert_eq!(reply.headers["content-type"], "application/json", "{body}");
        let message = reply.error();
        assert!(message.contains(says), "{body}: {message}");
    }
    let reply = server
        .call(Method::POST, "/api/v1/datasets/mini/submissions?model=m")
        .bearer(&admin)
        .header("idempotency-key", "")
        .expect(400)
        .await;
    assert!(reply.error().contains("Idempotency-Key"), "{}", reply.text);
}

#[tokio::test]
async fn the_web_and_the_command_line_share_one_naming_rule() {
    let (server, _) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let long = "x".repeat(101);
    let web = server
        .call(Method::POST, "/api/v1/admin/tokens")
        .bearer(&admin)
        .json(&json!({"name": long}))
        .expect(400)
        .await
        .error();

    let db = server.db_path();
    let output = enact_hub()
        .args(["token", "create", "--name", &long, "--db"])
        .arg(&db)
        .output()
        .expect("run enact-hub");
    assert!(!output.status.success());
    let cli = String::from_utf8_lossy(&output.stderr);
    assert!(cli.contains(&web), "the CLI says {cli:?}, the API {web:?}");

    // Annotator names: the same rule from both sides too.
    let output = enact_hub()
        .args(["annotator", "create", "--name", "two words", "--db"])
        .arg(&db)
        .output()
        .expect("run enact-hub");
    assert!(!output.status.success());
    let cli = String::from_utf8_lossy(&output.stderr);
    let hub = Hub::from(server.pool.clone());
    let Err(AppError::Invalid(rule)) =
        app::annotators::create(&hub, &tester(), "two words", false).await
    else {
        panic!("a name with a space is refused");
    };
    assert!(
        cli.contains(&rule),
        "the CLI says {cli:?}, the use case {rule:?}"
    );
}

#[tokio::test]
async fn a_draft_never_outlives_the_answer_that_finished_its_item() {
    use enact_hub::core::annotation::{Draft, Outcome, Session, Telemetry};
    let (server, records) = spawn_app_with_release().await;
    let annotator = crate::annotate::annotator(&server, "ann", false).await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    crate::annotate::assign(&server, annotator, &[&item]).await;
    let hub = Hub::from(server.pool.clone());
    let session = Session {
        annotator,
        name: "ann".to_owned(),
        is_admin: false,
        csrf_token: String::new(),
    };
    // The item is opened: this hub now holds "unfinished, with a draft" in memory.
    let opened = app::annotation::open(&hub, &session, "mini", &item)
        .await
        .expect("open");
    assert!(!opened.finished);
    let rowid = opened.item.rowid;
    // Another server (or a request this hub's memory has not seen) finishes it meanwhile.
    let mut conn = write_tx(&server.pool).await;
    let answer = enact_hub::core::verifier::Permutation::new(vec![2, 1]).expect("answer");
    assert!(
        enact_hub::store::annotations::finish(
            &mut conn,
            annotator,
            rowid,
            &Outcome::Answered(answer),
            &Telemetry::none(),
        )
        .await
        .expect("finish")
    );
    conn.commit().await.expect("commit");
    // The late save is refused by the store itself, and leaves no draft.
    let mut draft = Draft::empty(opened.item.summary.step_length);
    draft.slots = vec![Some(1), None];
    let refused = app::annotation::save_draft(&hub, &session, "mini", &item, &draft).await;
    let Err(AppError::Refused(Refusal::ItemFinished { item: finished })) = refused else {
        panic!("a save after the answer must be refused as finished: {refused:?}");
    };
    assert_eq!(finished, item);
    let drafts: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT count(*) FROM drafts WHERE item = $1").bind(rowid)
    )
    .expect("count");
    assert_eq!(drafts, 0);
    server.stop().await;
}
