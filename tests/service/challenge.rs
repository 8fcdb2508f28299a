//! Hidden test sets split for a challenge: the seeded split (what the draw says, kept across
//! restarts, refused where it must be), the board over the public part before the reveal
//! (figures recomputed here from the per-item answers), the reveal by hand and at a deadline
//! with each row's rank change, every account's submission count, and the selection limit and
//! the final ranking by the selected submissions.

use std::collections::BTreeSet;

use enact_hub::core::challenge::{Deadline, PublicShare, Stratum, draw_split};
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::{Direction, StepLength};
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

/// A server whose hidden dataset "mini" has `per_cell` items in each direction × L of 3 and 4.
async fn hidden_mini(per_cell: u32) -> (TestServer, Vec<Value>) {
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let written = write_balanced_release(&root, &[3, 4], per_cell);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    (server, records)
}

fn stratum(record: &Value) -> Stratum {
    let forward = record["type"]
        .as_str()
        .expect("type")
        .starts_with("forward");
    let states = record["key_frame_ids"]
        .as_array()
        .expect("key frames")
        .len();
    (
        if forward {
            Direction::Forward
        } else {
            Direction::Inverse
        },
        StepLength::new(states).expect("a step length"),
    )
}

fn id(record: &Value) -> String {
    record["id"].as_str().expect("id").to_owned()
}

/// The public item ids the documented draw gives: the items by id, `share`, `seed`.
fn expected_public(records: &[Value], share: f64, seed: u64) -> BTreeSet<String> {
    let mut sorted: Vec<&Value> = records.iter().collect();
    sorted.sort_by_key(|r| id(r));
    let strata: Vec<Stratum> = sorted.iter().map(|r| stratum(r)).collect();
    let parts = draw_split(&strata, PublicShare::new(share).expect("share"), seed);
    sorted
        .iter()
        .zip(parts)
        .filter(|(_, p)| *p == enact_hub::core::challenge::Part::Public)
        .map(|(r, _)| id(r))
        .collect()
}

async fn split(server: &TestServer, admin: &str, body: Value) -> Reply {
    server
        .call(Method::POST, "/api/v1/admin/datasets/mini/challenge/split")
        .bearer(admin)
        .json(&body)
        .send()
        .await
}

fn public_ids(view: &Value) -> BTreeSet<String> {
    view["public_item_ids"]
        .as_array()
        .expect("public_item_ids")
        .iter()
        .map(|v| v.as_str().expect("an id").to_owned())
        .collect()
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

async fn submit(server: &TestServer, token: &str, model: &str, body: String) -> i64 {
    let reply = submit_to(server, "mini", &format!("model={model}"), token, body).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    reply.id()
}

/// The indices of `records` in (or, with `inside` false, outside) `ids`.
fn indices(records: &[Value], ids: &BTreeSet<String>, inside: bool) -> Vec<usize> {
    records
        .iter()
        .enumerate()
        .filter(|(_, r)| ids.contains(&id(r)) == inside)
        .map(|(i, _)| i)
        .collect()
}

/// Task accuracy over the records in `part` of answers wrong on the indices in `wrong`: the
/// figure recomputed by hand.
fn task_accuracy(records: &[Value], part: &BTreeSet<String>, wrong: &[usize]) -> f64 {
    let in_part = indices(records, part, true);
    let right = in_part.iter().filter(|i| !wrong.contains(i)).count();
    right as f64 / in_part.len() as f64
}

/// The board's row of submission `id`.
fn row_of(board: &Value, id: i64) -> Value {
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|r| r["submission"] == id)
        .unwrap_or_else(|| panic!("no row of submission {id} in {board}"))
        .clone()
}

fn submissions_on(board: &Value) -> Vec<i64> {
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .filter_map(|r| r["submission"].as_i64())
        .collect()
}

async fn audit_count(server: &TestServer, action: &str, actor_kind: &str) -> i64 {
    db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar::<_, i64>(
            "SELECT count(*) FROM audit_log WHERE action = $1 AND actor_kind = $2"
        )
        .bind(action)
        .bind(actor_kind)
    )
    .expect("count audit entries")
}

#[tokio::test]
async fn a_split_is_the_documented_draw_kept_across_restarts_and_refused_where_it_must_be() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;

    // Refused before anything is stored: a share out of range names the field; a submitter
    // may not split; an unknown dataset is 404.
    let bad = split(&server, &admin, json!({"share": 1.5, "seed": 1})).await;
    assert_eq!(bad.status, 400, "{}", bad.text);
    assert!(bad.error().starts_with("share:"), "{}", bad.error());
    let refused = split(&server, &submitter, json!({"share": 0.5})).await;
    assert_eq!(refused.status, 403, "{}", refused.text);
    server
        .call(Method::POST, "/api/v1/admin/datasets/nope/challenge/split")
        .bearer(&admin)
        .json(&json!({"share": 0.5}))
        .expect(404)
        .await;
    // Not split yet: no challenge to read, select for or reveal.
    server
        .call(Method::GET, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .expect(409)
        .await;
    let reveal = server
        .call(Method::POST, "/api/v1/admin/datasets/mini/challenge/reveal")
        .bearer(&admin)
        .expect(409)
        .await;
    assert!(reveal.error().contains("not split"), "{}", reveal.error());
    assert_eq!(reveal.json()["code"], "challenge_not_split");
    assert_eq!(reveal.json()["details"]["dataset"], "mini");

    // A dataset whose answers are public cannot be split: the field is named.
    set_mini_answers(
        &server.pool,
        enact_hub::core::dataset::AnswerVisibility::Public,
    )
    .await;
    let public = split(&server, &admin, json!({"share": 0.5, "seed": 11})).await;
    assert_eq!(public.status, 409, "{}", public.text);
    assert!(public.error().contains("`answers`"), "{}", public.error());
    assert_eq!(public.json()["code"], "challenge_answers_public");
    set_mini_answers(
        &server.pool,
        enact_hub::core::dataset::AnswerVisibility::Hidden,
    )
    .await;

    let reply = split(&server, &admin, json!({"share": 0.5, "seed": 11})).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let view = reply.json();
    // Three items per stratum, half public: round(1.5) = 2 public, 1 private in each of four.
    assert_eq!(view["public_items"], 8);
    assert_eq!(view["private_items"], 4);
    assert_eq!(view["strata"].as_array().expect("strata").len(), 4);
    assert!(
        view["strata"]
            .as_array()
            .expect("strata")
            .iter()
            .all(|s| s["public"] == 2 && s["private"] == 1),
        "{view}"
    );
    let public = public_ids(&view);
    assert_eq!(public, expected_public(&records, 0.5, 11));
    assert_ne!(
        public,
        expected_public(&records, 0.5, 12),
        "the seed matters"
    );
    assert_eq!(audit_count(&server, "dataset.split", "account").await, 1);

    // A split is final.
    let again = split(&server, &admin, json!({"share": 0.25, "seed": 3})).await;
    assert_eq!(again.status, 409, "{}", again.text);
    assert!(again.error().contains("final"), "{}", again.error());
    assert_eq!(again.json()["code"], "challenge_already_split");
    assert_eq!(again.json()["details"]["seed"], 11);
    assert_eq!(again.json()["details"]["public_share"], "0.5");

    // A restart (the database opened again, nothing in memory) reads the same split.
    let reopened = enact_hub::app::Hub::open(&server.db_path())
        .await
        .expect("open the database again");
    let stored = enact_hub::app::challenge::status(&reopened, "mini")
        .await
        .expect("the challenge");
    assert_eq!(
        stored.public_item_ids.into_iter().collect::<BTreeSet<_>>(),
        public
    );
    assert_eq!((stored.seed, stored.public_share), (11, 0.5));
    reopened.close().await;
    server.stop().await;
}

#[tokio::test]
async fn before_the_reveal_everyone_sees_the_public_part_and_each_account_s_submissions() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    // Alice submits twice before the split, and once more that an admin hides.
    submit(&server, &alice, "m", answers(&records, &[0, 1, 2])).await;
    let view = split(&server, &admin, json!({"share": 0.5, "seed": 5}))
        .await
        .json();
    let public = public_ids(&view);
    let private: BTreeSet<String> = records
        .iter()
        .map(id)
        .filter(|i| !public.contains(i))
        .collect();
    // Alice is wrong on two public items and every private one; bob the other way round.
    let public_items = indices(&records, &public, true);
    let private_items = indices(&records, &public, false);
    let alice_wrong: Vec<usize> = public_items[..2]
        .iter()
        .chain(&private_items)
        .copied()
        .collect();
    let bob_wrong = private_items[..1].to_vec();
    let a = submit(&server, &alice, "m", answers(&records, &alice_wrong)).await;
    let hidden = submit(&server, &alice, "other", answers(&records, &[])).await;
    server
        .call(
            Method::PATCH,
            &format!("/api/v1/admin/submissions/{hidden}"),
        )
        .bearer(&admin)
        .json(&json!({"visibility": "hidden"}))
        .expect(200)
        .await;
    let b = submit(&server, &bob, "m", answers(&records, &bob_wrong)).await;

    let default = board(&server, "").await;
    assert_eq!(default["challenge"]["part"], "public");
    assert_eq!(default["challenge"]["public_items"], 8);
    assert_eq!(default["challenge"]["private_items"], 4);
    assert_eq!(default["challenge"]["revealed_at"], Value::Null);
    let alice_row = row_of(&default, a);
    let bob_row = row_of(&default, b);
    // The figures over the public part, as recomputed here from the answers.
    assert_eq!(
        alice_row["overall"]["task_accuracy"].as_f64(),
        Some(task_accuracy(&records, &public, &alice_wrong))
    );
    assert_eq!(alice_row["overall"]["task_accuracy"].as_f64(), Some(0.75));
    assert_eq!(alice_row["overall"]["count"], 8);
    assert_eq!(bob_row["overall"]["task_accuracy"].as_f64(), Some(1.0));
    assert_eq!(alice_row["coverage"].as_f64(), Some(1.0));
    // Per direction too: each direction has 4 public items.
    let forward_public: BTreeSet<String> = public
        .iter()
        .filter(|i| i.contains("forward"))
        .cloned()
        .collect();
    assert_eq!(alice_row["forward"]["total"]["count"], 4);
    assert_eq!(
        alice_row["forward"]["total"]["task_accuracy"].as_f64(),
        Some(task_accuracy(&records, &forward_public, &alice_wrong))
    );
    // Alice: three submissions to the dataset, one hidden; two of model "m" published.
    assert_eq!(alice_row["account_submissions"], 3);
    assert_eq!(alice_row["attempts"], 2);
    assert_eq!(bob_row["account_submissions"], 1);
    // The submitters' own scores are over the public part too; an admin sees every item.
    let own = server
        .call(Method::GET, &format!("/api/v1/submissions/{a}"))
        .bearer(&alice)
        .expect(200)
        .await
        .json();
    assert_eq!(own["scores"]["report"]["overall"]["task_accuracy"], 0.75);
    assert_eq!(own["scores"]["coverage"]["dataset_items"], 8);
    let whole = server
        .call(Method::GET, &format!("/api/v1/submissions/{a}"))
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(
        whole["scores"]["report"]["overall"]["task_accuracy"].as_f64(),
        Some(6.0 / 12.0)
    );
    // Posting one shows the public part's figures at once.
    let posted = submit_to(
        &server,
        "mini",
        "model=m2",
        &bob,
        answers(&records, &private_items),
    )
    .await;
    assert_eq!(posted.status, 201, "{}", posted.text);
    assert_eq!(
        posted.json()["scores"]["report"]["overall"]["task_accuracy"],
        1.0
    );

    // So is a comparison of two rows.
    let compare = format!("/api/v1/datasets/mini/compare?a={a}&b={b}");
    let paired = server.call(Method::GET, &compare).expect(200).await.json();
    assert_eq!(paired["overall"]["n"], 8);
    assert_eq!(paired["overall"]["a_task_accuracy"], 0.75);

    // The private part is for admins until the reveal.
    let refused = server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?part=private",
        )
        .expect(403)
        .await;
    assert!(
        refused.error().contains("part=private"),
        "{}",
        refused.error()
    );
    assert_eq!(refused.json()["code"], "private_part_hidden");
    assert_eq!(refused.json()["details"]["dataset"], "mini");
    server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?part=private",
        )
        .bearer(&alice)
        .expect(403)
        .await;
    let preview = server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?part=private",
        )
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(preview["challenge"]["part"], "private");
    // The final ranking as a reveal now would make it: each account's latest submission (none
    // is selected), over the private part.
    let mut finalists = submissions_on(&preview);
    finalists.sort_unstable();
    assert_eq!(finalists, vec![a, posted.id()]);
    assert_eq!(
        row_of(&preview, a)["overall"]["task_accuracy"].as_f64(),
        Some(task_accuracy(&records, &private, &alice_wrong))
    );
    assert_eq!(row_of(&preview, posted.id())["overall"]["count"], 4);
    // Even with every submission asked for: the final ranking has the finalists only.
    let all = server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?part=private&all=1",
        )
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert!(
        !submissions_on(&all).contains(&b),
        "only the finalists: {all}"
    );

    // The page says so, with the counts.
    let html = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await
        .text;
    assert!(
        html.contains("over the public part only, 8 of the 12 items"),
        "{html}"
    );
    assert!(html.contains("3 submissions by this account"), "{html}");
    assert!(!html.contains("Preview the final ranking"), "{html}");
    server.stop().await;
}

/// Splits "mini" (3 items per stratum, half public, seed 9) and posts three accounts'
/// answers built so that the ranks turn over at the reveal: "top" is right on the public part
/// only, "bottom" on the private part only, "middle" on half of each. Their submission ids
/// and the public ids.
async fn turnover(
    server: &TestServer,
    records: &[Value],
    admin: &str,
) -> (Vec<(String, i64)>, BTreeSet<String>) {
    let view = split(server, admin, json!({"share": 0.5, "seed": 9}))
        .await
        .json();
    let public = public_ids(&view);
    let public_items = indices(records, &public, true);
    let private_items = indices(records, &public, false);
    let mut ids = Vec::new();
    for (name, wrong) in [
        ("top", private_items.clone()),
        ("bottom", public_items.clone()),
        (
            "middle",
            public_items[..4]
                .iter()
                .chain(&private_items[..2])
                .copied()
                .collect(),
        ),
    ] {
        let (_, token) = api_token(&server.pool, name, Role::Submitter, None, None).await;
        ids.push((
            name.to_owned(),
            submit(server, &token, "m", answers(records, &wrong)).await,
        ));
    }
    (ids, public)
}

/// `(submission, rank, public_rank, private_rank, rank_change)` of each ranked row.
fn standings(board: &Value) -> Vec<(i64, Value, Value, Value, Value)> {
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| {
            (
                r["submission"].as_i64().expect("a submission row"),
                r["rank"].clone(),
                r["standing"]["public_rank"].clone(),
                r["standing"]["private_rank"].clone(),
                r["standing"]["rank_change"].clone(),
            )
        })
        .collect()
}

#[tokio::test]
async fn a_reveal_by_hand_ranks_over_the_private_part_and_shows_each_rank_change() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (ids, public) = turnover(&server, &records, &admin).await;
    let [(_, top), (_, bottom), (_, middle)] = ids.as_slice() else {
        panic!("three submissions");
    };
    let before = board(&server, "").await;
    assert_eq!(submissions_on(&before), vec![*top, *middle, *bottom]);
    assert!(before["rows"][0].get("standing").is_none(), "{before}");
    // A signed statement carries the whole dataset's scores: its submitter gets it only after
    // the reveal (an admin at any time).
    let (_, top_token) = api_token(&server.pool, "top", Role::Submitter, None, None).await;
    let statement = format!("/api/v1/submissions/{top}/statement");
    let withheld = server
        .call(Method::GET, &statement)
        .bearer(&top_token)
        .expect(409)
        .await;
    assert!(
        withheld.error().contains("revealed"),
        "{}",
        withheld.error()
    );
    server
        .call(Method::GET, &statement)
        .bearer(&admin)
        .expect(200)
        .await;

    let revealed = server
        .call(Method::POST, "/api/v1/admin/datasets/mini/challenge/reveal")
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(revealed["revealed_by"], "hand");
    assert_eq!(audit_count(&server, "dataset.reveal", "account").await, 1);

    server
        .call(Method::GET, &statement)
        .bearer(&top_token)
        .expect(200)
        .await;
    let after = board(&server, "").await;
    assert_eq!(after["challenge"]["part"], "private");
    assert!(after["challenge"]["revealed_at"].is_string());
    // Private figures by hand: top 0 of 4, bottom 4 of 4, middle 2 of 4.
    let private: BTreeSet<String> = records
        .iter()
        .map(id)
        .filter(|i| !public.contains(i))
        .collect();
    assert_eq!(row_of(&after, *bottom)["overall"]["count"], 4);
    assert_eq!(
        row_of(&after, *middle)["overall"]["task_accuracy"].as_f64(),
        Some(task_accuracy(
            &records,
            &private,
            &indices(&records, &public, true)[..4]
                .iter()
                .chain(&indices(&records, &public, false)[..2])
                .copied()
                .collect::<Vec<_>>()
        ))
    );
    assert_eq!(
        standings(&after),
        vec![
            (*bottom, json!(1), json!(3), json!(1), json!(2)),
            (*middle, json!(2), json!(2), json!(2), json!(0)),
            (*top, json!(3), json!(1), json!(3), json!(-2)),
        ]
    );
    // The public part's board stays readable, as it stood.
    let public_board = board(&server, "part=public").await;
    assert_eq!(public_board["challenge"]["part"], "public");
    assert_eq!(submissions_on(&public_board), vec![*top, *middle, *bottom]);
    // The page shows the ranks and the change.
    let html = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await
        .text;
    assert!(html.contains("Final ranking"), "{html}");
    assert!(
        html.contains("public rank 3, private rank 1: up 2 places"),
        "{html}"
    );
    assert!(
        html.contains("public rank 1, private rank 3: down 2 places"),
        "{html}"
    );
    // Everything is fixed now.
    server
        .call(Method::POST, "/api/v1/admin/datasets/mini/challenge/reveal")
        .bearer(&admin)
        .expect(409)
        .await;
    let settings = server
        .call(Method::PATCH, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .json(&json!({"selection_limit": 1}))
        .expect(409)
        .await;
    assert!(
        settings.error().contains("revealed"),
        "{}",
        settings.error()
    );
    assert_eq!(settings.json()["code"], "challenge_revealed");
    assert_eq!(settings.json()["details"]["how"], "hand");
    server
        .call(Method::PUT, &format!("/api/v1/submissions/{top}/selection"))
        .bearer(&admin)
        .expect(409)
        .await;
    server.stop().await;
}

#[tokio::test]
async fn a_deadline_reveals_the_private_part_at_the_first_read_after_it_once() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (ids, _) = turnover(&server, &records, &admin).await;
    let bad = server
        .call(Method::PATCH, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .json(&json!({"reveal_at": "next tuesday"}))
        .expect(400)
        .await;
    assert!(bad.error().starts_with("reveal_at:"), "{}", bad.error());

    // A deadline a few seconds ahead: the board is built (and kept) before it...
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("time");
    let deadline = now.as_secs() + 4;
    let soon = Deadline::from_unix(deadline as i64).text();
    let set = server
        .call(Method::PATCH, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .json(&json!({"reveal_at": soon, "selection_limit": 2}))
        .expect(200)
        .await
        .json();
    assert_eq!(set["reveal_at"], json!(soon));
    assert_eq!(set["selection_limit"], 2);
    let before = board(&server, "").await;
    assert_eq!(before["challenge"]["part"], "public");
    assert_eq!(before["challenge"]["reveal_at"], json!(soon));
    let html = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await
        .text;
    assert!(html.contains(&format!("revealed at {soon}")), "{html}");

    // ...and not served once it has passed: the next read reveals, once, as the server.
    let passed = std::time::Duration::from_secs(deadline + 1).saturating_sub(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .expect("time"),
    );
    tokio::time::sleep(passed).await;
    let after = board(&server, "").await;
    assert_eq!(after["challenge"]["part"], "private", "{after}");
    assert_eq!(
        submissions_on(&after),
        vec![ids[1].1, ids[2].1, ids[0].1],
        "bottom, middle, top"
    );
    board(&server, "").await;
    server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await;
    assert_eq!(audit_count(&server, "dataset.reveal", "server").await, 1);
    let status = server
        .call(Method::GET, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(status["revealed_by"], "deadline");
    server.stop().await;
}

#[tokio::test]
async fn a_deadline_in_the_past_reveals_at_the_next_read() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (ids, _) = turnover(&server, &records, &admin).await;
    assert_eq!(board(&server, "").await["challenge"]["part"], "public");
    server
        .call(Method::PATCH, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .json(&json!({"reveal_at": "2020-01-01T01:00:00+01:00"}))
        .expect(200)
        .await;
    let after = board(&server, "").await;
    assert_eq!(after["challenge"]["part"], "private");
    assert_eq!(after["challenge"]["reveal_at"], "2020-01-01T00:00:00Z");
    let top = row_of(&after, ids[0].1);
    assert_eq!(top["standing"]["rank_change"], -2);
    assert_eq!(audit_count(&server, "dataset.reveal", "server").await, 1);
    server.stop().await;
}

#[tokio::test]
async fn the_selection_limit_is_kept_and_the_final_ranking_uses_the_selected_submission() {
    let (server, records) = hidden_mini(3).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    // Selecting needs a split dataset.
    let early = submit(&server, &alice, "m", answers(&records, &[])).await;
    let unsplit = server
        .call(
            Method::PUT,
            &format!("/api/v1/submissions/{early}/selection"),
        )
        .bearer(&alice)
        .expect(409)
        .await;
    assert!(unsplit.error().contains("not split"), "{}", unsplit.error());

    let view = split(&server, &admin, json!({"share": 0.5, "seed": 21}))
        .await
        .json();
    let public = public_ids(&view);
    let private_items = indices(&records, &public, false);
    server
        .call(Method::PATCH, "/api/v1/admin/datasets/mini/challenge")
        .bearer(&admin)
        .json(&json!({"selection_limit": 1}))
        .expect(200)
        .await;
    // Alice: "good" is right everywhere; "worse", posted later, is wrong on the private part.
    let good = submit(&server, &alice, "good", answers(&records, &[])).await;
    let worse = submit(&server, &alice, "worse", answers(&records, &private_items)).await;
    let bob_latest = submit(&server, &bob, "m", answers(&records, &private_items[..1])).await;

    let select = |id: i64, token: String, status: u16| {
        let server = &server;
        async move {
            server
                .call(Method::PUT, &format!("/api/v1/submissions/{id}/selection"))
                .bearer(&token)
                .expect(status)
                .await
        }
    };
    let chosen = select(good, alice.clone(), 200).await.json();
    assert_eq!(chosen["selected"], json!([good]));
    assert_eq!(chosen["counted"], json!([good]));
    assert_eq!(chosen["selection_limit"], 1);
    // Again: nothing changes. Beyond the limit: refused, naming the limit and the selection.
    select(good, alice.clone(), 200).await;
    let over = select(worse, alice.clone(), 409).await;
    assert!(over.error().contains("selection limit"), "{}", over.error());
    assert!(over.error().contains(" is 1 "), "{}", over.error());
    assert!(over.error().contains(&good.to_string()), "{}", over.error());
    assert_eq!(over.json()["code"], "selection_limit_reached");
    assert_eq!(over.json()["details"]["limit"], 1);
    assert_eq!(over.json()["details"]["selected"], good.to_string());
    // Another account's submission is answered like a missing one.
    select(good, bob.clone(), 404).await;
    // Taken out and put back, audited each time it changed.
    server
        .call(
            Method::DELETE,
            &format!("/api/v1/submissions/{good}/selection"),
        )
        .bearer(&alice)
        .expect(200)
        .await;
    let mine = server
        .call(Method::GET, "/api/v1/datasets/mini/selection")
        .bearer(&alice)
        .expect(200)
        .await
        .json();
    // Nothing selected: the latest counts.
    assert_eq!(mine["selected"], json!([]));
    assert_eq!(mine["counted"], json!([worse]));
    select(good, alice.clone(), 200).await;
    assert_eq!(
        audit_count(&server, "submission.select", "account").await,
        3
    );

    server
        .call(Method::POST, "/api/v1/admin/datasets/mini/challenge/reveal")
        .bearer(&admin)
        .expect(200)
        .await;
    let final_board = board(&server, "").await;
    // Alice's final row is the one she selected, not her latest; bob, who selected none, is
    // ranked by his latest.
    let mut ranked = submissions_on(&final_board);
    ranked.sort_unstable();
    assert_eq!(ranked, vec![good, bob_latest]);
    assert_eq!(row_of(&final_board, good)["overall"]["task_accuracy"], 1.0);
    assert_eq!(row_of(&final_board, good)["rank"], 1);
    assert_eq!(row_of(&final_board, good)["account_submissions"], 3);
    let _ = early;
    server.stop().await;
}

#[tokio::test]
async fn an_admin_splits_sets_and_reveals_on_the_admin_page() {
    use crate::annotate::{annotator, logged_in_on};

    let (server, _) = hidden_mini(3).await;
    annotator(&server, "root", true).await;
    let (mut browser, csrf) = logged_in_on(&server, "root", "/admin/challenges").await;
    let (status, page) = browser.text("/admin/challenges?dataset=mini").await;
    assert_eq!(status, 200);
    assert!(page.contains("Not split."), "{page}");

    // A bad share is refused naming the field; a good one splits and comes back to the page.
    let bad = browser
        .post_form(
            "/admin/challenges/split",
            &[("csrf", &csrf), ("dataset", "mini"), ("share", "2")],
        )
        .await;
    assert_eq!(bad.status(), 400);
    assert!(bad.text().await.expect("page").contains("share:"));
    let split = browser
        .post_form(
            "/admin/challenges/split",
            &[
                ("csrf", &csrf),
                ("dataset", "mini"),
                ("share", "0.5"),
                ("seed", "3"),
            ],
        )
        .await;
    assert_eq!(split.status(), 303);
    let (_, page) = browser.text("/admin/challenges?dataset=mini").await;
    assert!(page.contains("8 public and 4 private items"), "{page}");

    let set = browser
        .post_form(
            "/admin/challenges/settings",
            &[
                ("csrf", &csrf),
                ("dataset", "mini"),
                ("reveal_at", "2099-01-01T00:00:00Z"),
                ("selection_limit", "2"),
            ],
        )
        .await;
    assert_eq!(set.status(), 303);
    let (_, page) = browser.text("/admin/challenges").await;
    assert!(
        page.contains("split; reveals at 2099-01-01T00:00:00Z"),
        "{page}"
    );
    // An admin's session previews the final ranking on the public page.
    let (status, preview) = browser.text("/leaderboard/mini?part=private").await;
    assert_eq!(status, 200);
    assert!(preview.contains("Admin preview"), "{preview}");
    let (status, refused) = crate::annotate::Browser::new(&server)
        .text("/leaderboard/mini?part=private")
        .await;
    assert_eq!(status, 403);
    assert!(
        refused.contains("is not revealed yet (it will be at 2099-01-01"),
        "{refused}"
    );
    // A reader of the pages in Chinese is told why in Chinese.
    let (status, refused) = crate::annotate::Browser::new(&server)
        .in_language("zh-CN")
        .text("/leaderboard/mini?part=private")
        .await;
    assert_eq!(status, 403);
    assert!(
        refused.contains("私有部分尚未揭晓（将于 2099年1月1日"),
        "{refused}"
    );

    let reveal = browser
        .post_form(
            "/admin/challenges/reveal",
            &[("csrf", &csrf), ("dataset", "mini")],
        )
        .await;
    assert_eq!(reveal.status(), 303);
    let (_, page) = browser.text("/admin/challenges?dataset=mini").await;
    assert!(page.contains("(by hand)"), "{page}");
    assert_eq!(audit_count(&server, "dataset.split", "annotator").await, 1);
    assert_eq!(
        audit_count(&server, "challenge.settings", "annotator").await,
        1
    );
    assert_eq!(audit_count(&server, "dataset.reveal", "annotator").await, 1);
    server.stop().await;
}
