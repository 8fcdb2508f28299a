//! The leaderboard at size: one row per account and model, tie ranks, sorting and paging in
//! the API and the page, and the board kept in memory until something it shows changes.

use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::annotate::{annotator, assign, logged_in_on};
use crate::helpers::*;

/// Submits `body` as `model` with `token`; the new submission's id.
pub async fn submit(server: &TestServer, token: &str, model: &str, body: String) -> i64 {
    let reply = submit_to(server, "mini", &format!("model={model}"), token, body).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    reply.id()
}

async fn board(server: &TestServer, query: &str) -> Value {
    server
        .call(
            Method::GET,
            &format!("/api/v1/datasets/mini/leaderboard?{query}"),
        )
        .expect(200)
        .await
        .json()
}

/// `(submission, rank, attempts)` of each row, Human row included.
fn rows(board: &Value) -> Vec<(Option<i64>, Option<u64>, u64)> {
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            (
                r["submission"].as_i64(),
                r["rank"].as_u64(),
                r["attempts"].as_u64().expect("attempts"),
            )
        })
        .collect()
}

#[tokio::test]
async fn one_row_per_account_and_model_with_its_history_and_every_row_on_request() {
    let (server, records) = spawn_app_with_release().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    let a1 = submit(&server, &alice, "m", answers(&records, &[0, 1, 2, 3])).await;
    let a2 = submit(&server, &alice, "m", answers(&records, &[])).await;
    let an = submit(&server, &alice, "n", answers(&records, &[0, 1])).await;
    let b = submit(&server, &bob, "m", answers(&records, &[0])).await;

    // Alice's latest "m" is her entry, with both attempts counted; bob's "m" is his own row.
    let default = board(&server, "").await;
    assert_eq!(
        rows(&default),
        vec![
            (Some(a2), Some(1), 2),
            (Some(b), Some(2), 1),
            (Some(an), Some(3), 1)
        ]
    );
    assert_eq!(default["entries"], 3);
    assert_eq!(default["every_submission"], false);
    let history = default["rows"][0]["history"]
        .as_str()
        .expect("a history link");
    let every_m = server.call(Method::GET, history).expect(200).await.json();
    assert_eq!(
        rows(&every_m),
        vec![(Some(a2), Some(1), 1), (Some(a1), Some(2), 1)]
    );
    assert!(
        every_m["rows"]
            .as_array()
            .expect("rows")
            .iter()
            .all(|r| r["account"] == "alice" && r["model"] == "m")
    );

    let all = board(&server, "all=1").await;
    assert_eq!(all["entries"], 4);
    assert_eq!(all["rows"].as_array().expect("rows").len(), 4);

    // The page says the same: one row per model, with the attempts linked.
    let html = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await
        .text;
    assert_eq!(html.matches("<tr>").count() - 3, 3, "three table rows");
    assert!(html.contains("2 attempts"), "{html}");
    assert!(html.contains("Every submission"));
    server.stop().await;
}

#[tokio::test]
async fn equal_scores_share_a_rank_and_the_next_rank_skips() {
    let (server, records) = spawn_app_with_release().await;
    let mut ids = Vec::new();
    for (name, wrong) in [
        ("a", vec![]),
        ("b", vec![0]),
        ("c", vec![0]),
        ("d", vec![0, 1]),
    ] {
        let (_, token) = api_token(&server.pool, name, Role::Submitter, None, None).await;
        ids.push(submit(&server, &token, "m", answers(&records, &wrong)).await);
    }
    let ranks: Vec<Option<u64>> = rows(&board(&server, "").await)
        .into_iter()
        .map(|(_, rank, _)| rank)
        .collect();
    assert_eq!(ranks, vec![Some(1), Some(2), Some(2), Some(4)]);
    server.stop().await;
}

#[tokio::test]
async fn any_column_sorts_and_pages_in_the_api_and_the_page() {
    let (server, records) = spawn_app_with_release().await;
    // Records 0 and 2 are forward, 1 and 3 inverse: "fwd" is right forward only, "inv" inverse
    // only, "all" everywhere, "none" nowhere.
    let mut id = std::collections::BTreeMap::new();
    for (name, wrong) in [
        ("none", vec![0, 1, 2, 3]),
        ("fwd", vec![1, 3]),
        ("inv", vec![0, 2]),
        ("all", vec![]),
    ] {
        let (_, token) = api_token(&server.pool, name, Role::Submitter, None, None).await;
        id.insert(
            name,
            submit(&server, &token, name, answers(&records, &wrong)).await,
        );
    }
    assert_eq!(
        records
            .iter()
            .map(|r| r["type"].as_str().expect("type").contains("forward"))
            .collect::<Vec<_>>(),
        vec![true, false, true, false],
        "the release alternates forward and inverse records"
    );
    // By inverse TA, two to a page: page 1 holds "all" and "inv" (tied at 100.0), page 2 the rest.
    let first = board(&server, "sort=inverse_ta&per_page=2").await;
    assert_eq!(
        rows(&first),
        vec![(Some(id["all"]), Some(1), 1), (Some(id["inv"]), Some(1), 1)],
        "a tie lists the better overall TA first"
    );
    assert_eq!(
        (first["pages"].as_u64(), first["entries"].as_u64()),
        (Some(2), Some(4))
    );
    assert!(first["prev"].is_null());
    let next = first["next"].as_str().expect("a next page");
    let second = server.call(Method::GET, next).expect(200).await.json();
    let ranks: Vec<Option<u64>> = rows(&second).iter().map(|r| r.1).collect();
    assert_eq!(
        ranks,
        vec![Some(3), Some(3)],
        "fwd and none tie at 0.0 inverse TA"
    );
    assert!(second["next"].is_null());
    assert!(second["prev"].as_str().is_some());

    let by_forward = board(&server, "sort=forward_ta").await;
    let order: Vec<Option<i64>> = rows(&by_forward).iter().map(|r| r.0).collect();
    assert_eq!(order[..2], [Some(id["all"]), Some(id["fwd"])]);

    // The page: the chosen column is marked, and pages link to each other.
    let html = server
        .call(
            Method::GET,
            "/leaderboard/mini?sort=inverse_ta&per_page=2&page=2",
        )
        .expect(200)
        .await
        .text;
    assert!(
        html.contains("Ranked by <strong>inverse TA</strong>"),
        "{html}"
    );
    assert!(html.contains("page 2 of 2"), "{html}");
    assert!(html.contains("rel=\"prev\""));
    assert!(html.contains(">fwd<") && html.contains(">none<") && !html.contains(">inv<"));

    // Bad requests name what is wrong.
    for (query, says) in [
        ("sort=sideways", "sort:"),
        ("per_page=0", "per_page"),
        ("page=x", "page"),
        ("all=maybe", "all"),
    ] {
        let reply = server
            .call(
                Method::GET,
                &format!("/api/v1/datasets/mini/leaderboard?{query}"),
            )
            .expect(400)
            .await;
        assert!(reply.error().contains(says), "{query}: {}", reply.text);
    }
    server.stop().await;
}

/// The board's entity tag and JSON.
async fn tagged(server: &TestServer) -> (String, Value) {
    let reply = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .expect(200)
        .await;
    let etag = reply.headers["etag"].to_str().expect("an ETag").to_owned();
    (etag, reply.json())
}

/// A board with one submission ("m" of account "team"), read once: the server, the records,
/// team's and an admin's tokens, the submission's id, and the board's entity tag.
async fn read_board() -> (TestServer, Vec<Value>, String, String, i64, String) {
    let (server, records) = spawn_app_with_release().await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let first = submit(&server, &team, "m", answers(&records, &[0])).await;
    let (etag, before) = tagged(&server).await;
    assert_eq!(rows(&before), vec![(Some(first), Some(1), 1)]);
    (server, records, team, admin, first, etag)
}

#[tokio::test]
async fn an_unchanged_board_keeps_its_tag_and_answers_304() {
    let (server, _, _, _, _, etag) = read_board().await;
    let (again, _) = tagged(&server).await;
    assert_eq!(again, etag);
    let reply = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .header("if-none-match", &etag)
        .send()
        .await;
    assert_eq!(reply.status, 304);
    assert!(reply.text.is_empty());
    let page = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await;
    let page_tag = page.headers["etag"].to_str().expect("tag").to_owned();
    assert_ne!(
        page_tag, etag,
        "the page and the JSON are different entities"
    );
    let reply = server
        .call(Method::GET, "/leaderboard/mini")
        .header("if-none-match", &page_tag)
        .send()
        .await;
    assert_eq!(reply.status, 304);
    // Another page of the same board is another entity.
    let other = server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?sort=overall_pa",
        )
        .expect(200)
        .await;
    assert_ne!(other.headers["etag"], etag.as_str());
    server.stop().await;
}

#[tokio::test]
async fn a_stored_submission_drops_the_board() {
    let (server, records, team, _, _, etag) = read_board().await;
    let second = submit(&server, &team, "n", answers(&records, &[])).await;
    let (after, board) = tagged(&server).await;
    assert_ne!(after, etag);
    assert_eq!(rows(&board).len(), 2);
    assert_eq!(board["rows"][0]["submission"], second);
    server.stop().await;
}

#[tokio::test]
async fn a_visibility_change_drops_the_board() {
    let (server, _, _, admin, first, etag) = read_board().await;
    server
        .call(Method::PATCH, &format!("/api/v1/admin/submissions/{first}"))
        .bearer(&admin)
        .json(&json!({"visibility": "hidden"}))
        .expect(200)
        .await;
    let (after, board) = tagged(&server).await;
    assert_ne!(after, etag);
    assert_eq!(rows(&board), vec![]);
    server.stop().await;
}

#[tokio::test]
async fn a_baseline_flag_drops_the_board() {
    let (server, _, _, admin, first, etag) = read_board().await;
    server
        .call(Method::PATCH, &format!("/api/v1/admin/submissions/{first}"))
        .bearer(&admin)
        .json(&json!({"baseline": true}))
        .expect(200)
        .await;
    let (after, board) = tagged(&server).await;
    assert_ne!(after, etag);
    // Shown, no longer ranked.
    assert_eq!(rows(&board), vec![(Some(first), None, 1)]);
    assert_eq!(board["rows"][0]["baseline"], true);
    server.stop().await;
}

#[tokio::test]
async fn an_annotators_answer_drops_the_board_for_the_human_row() {
    let (server, records, _, _, _, etag) = read_board().await;
    let annotator_id = annotator(&server, "ann", false).await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    assign(&server, annotator_id, &[&item]).await;
    let (mut ann, csrf) = logged_in_on(&server, "ann", "/annotate").await;
    ann.get(&format!("/annotate/mini/{item}")).await;
    let r = ann
        .post_json(
            &format!("/annotate/mini/{item}/submit"),
            Some(&csrf),
            &json!({
                "slots": records[0]["gt_answer"],
                "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}
            }),
        )
        .await;
    assert_eq!(r.status(), 200);
    let (after, board) = tagged(&server).await;
    assert_ne!(after, etag);
    assert!(
        board["rows"]
            .as_array()
            .expect("rows")
            .iter()
            .any(|r| r["source"] == "human"),
        "{board}"
    );
    server.stop().await;
}

/// Publishes `total` submissions to "mini" from `accounts` accounts, each (account, model) pair
/// its own entry: four are scored for real (right, and wrong on one, two and every record), the
/// rest copy their scores row by row in SQL, which is all a board reads.
pub async fn crowded_board(server: &TestServer, records: &[Value], total: usize, accounts: usize) {
    let mut tokens = Vec::new();
    for a in 0..accounts {
        let name = format!("team-{a:02}");
        let (id, token) = api_token(&server.pool, &name, Role::Submitter, None, None).await;
        tokens.push((id, token));
    }
    let mut templates = Vec::new();
    for (k, wrong) in [vec![], vec![0], vec![0, 1], vec![0, 1, 2, 3]]
        .iter()
        .enumerate()
    {
        let model = format!("model-{k:03}");
        templates.push(
            submit(
                server,
                &tokens[k % accounts].1,
                &model,
                answers(records, wrong),
            )
            .await,
        );
    }
    let mut tx = server.pool.begin().await.expect("begin");
    for i in templates.len()..total {
        let (token, _) = &tokens[i % accounts];
        let model = format!("model-{i:03}");
        enact_hub::store::on_db!(&mut tx, |c| sqlx::query(
            "INSERT INTO submissions (dataset, account, token, body_sha256, model, scores) \
             SELECT s.dataset, t.account, t.id, s.body_sha256, $1, s.scores \
             FROM submissions s, api_tokens t WHERE s.id = $2 AND t.id = $3",
        )
        .bind(&model)
        .bind(templates[i % templates.len()])
        .bind(token)
        .execute(&mut *c)
        .await
        .map(|_| ()))
        .expect("copy a submission");
    }
    tx.commit().await.expect("commit");
}

#[tokio::test]
async fn a_thousand_submissions_make_a_board_of_pages() {
    let (server, records) = spawn_app_with_release().await;
    crowded_board(&server, &records, 1000, 50).await;
    let first = board(&server, "").await;
    assert_eq!(first["entries"], 1000);
    assert_eq!(first["pages"], 20);
    assert_eq!(first["rows"].as_array().expect("rows").len(), 50);
    let last = board(&server, "page=20").await;
    let ranks: Vec<Option<u64>> = rows(&last).iter().map(|r| r.1).collect();
    // A quarter of the copies are wrong everywhere: they tie for the last rank, 751.
    assert!(ranks.iter().all(|r| *r == Some(751)), "{ranks:?}");
    let html = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await
        .text;
    assert!(html.contains("page 1 of 20"));
    assert_eq!(html.matches("<tr>").count() - 3, 50, "fifty table rows");
    assert_eq!(
        html.matches("<polyline").count(),
        2 * 10,
        "the top ten in each panel"
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn readers_that_miss_together_share_one_build_and_a_change_starts_another() {
    use enact_hub::app::{Hub, leaderboard};
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let id = submit(&server, &token, "m1", answers(&records, &[0])).await;
    let hub = Hub::from(server.pool.clone());
    let read_together = |n: usize| {
        let hub = hub.clone();
        async move {
            let reads = (0..n).map(|_| {
                let hub = hub.clone();
                tokio::spawn(async move { leaderboard::board(&hub, "mini").await })
            });
            let mut boards = Vec::new();
            for read in reads.collect::<Vec<_>>() {
                boards.push(read.await.expect("task").expect("board"));
            }
            boards
        }
    };
    // Sixteen readers on an empty cache: one build, one board for all.
    let boards = read_together(16).await;
    assert_eq!(enact_hub::app::leaderboard::board_builds(&hub), 1);
    assert!(boards.iter().all(|b| std::sync::Arc::ptr_eq(b, &boards[0])));
    assert_eq!(boards[0].rows.len(), 1);
    // Kept: later readers build nothing.
    read_together(4).await;
    assert_eq!(enact_hub::app::leaderboard::board_builds(&hub), 1);
    assert!(!boards[0].rows[0].baseline);
    // A change (the submission marked a baseline) starts one new build, which the next
    // readers share, and which shows what changed.
    enact_hub::app::submissions::update_listing(&hub, &tester(), &id.to_string(), Some(true), None)
        .await
        .expect("listing");
    let boards = read_together(16).await;
    assert_eq!(enact_hub::app::leaderboard::board_builds(&hub), 2);
    assert!(boards.iter().all(|b| std::sync::Arc::ptr_eq(b, &boards[0])));
    assert!(boards[0].rows[0].baseline);
    // A dataset that does not exist is refused to every reader, and nothing is kept.
    let missing = leaderboard::board(&hub, "nope").await;
    assert!(matches!(
        missing,
        Err(enact_hub::app::AppError::Refused(
            enact_hub::app::refusal::Refusal::NoDataset { .. }
        ))
    ));
    server.stop().await;
}
