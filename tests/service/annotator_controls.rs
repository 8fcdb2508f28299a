//! Annotator controls: a paused queue refuses its annotator's work and says so in their
//! language (and a command-line pause reaches a running server), resuming restores it with its
//! drafts; a handover moves exactly the unfinished items with a balanced split and leaves the
//! finished answers where they were; attention checks are mixed into the queues, show their
//! instruction, are judged against it, counted on the quality API and page, and kept out of
//! the Human row and of agreement. Every change is audited.

use std::collections::{BTreeMap, HashSet};

use enact_hub::app::Hub;
use enact_hub::app::annotation::{self, Assignment};
use enact_hub::core::audit::AuditFilter;
use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::annotate::{Browser, annotator, logged_in_on};
use crate::helpers::*;
use crate::quality::{assign_listed, work_queue};

/// Items per direction × L (L = 3 and 4): 24 items, forward L = 3 first (records 0-5), then
/// inverse L = 3 (6-11), forward L = 4 (12-17), inverse L = 4 (18-23).
const PER_CELL: u32 = 6;

/// A server with the 24-item release as "mini", its item ids in order, and an admin token.
async fn server_with_items() -> (TestServer, Vec<Value>, String) {
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let written = write_balanced_release(&root, &[3, 4], PER_CELL);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    let (_, token) = api_token(&server.pool, "boss", Role::Admin, None, None).await;
    (server, records, token)
}

fn id(record: &Value) -> String {
    record["id"].as_str().expect("id").to_owned()
}

fn labels(value: &Value) -> Vec<u8> {
    value
        .as_array()
        .expect("a label list")
        .iter()
        .map(|v| u8::try_from(v.as_u64().expect("a label")).expect("small"))
        .collect()
}

/// Runs `enact-hub` with `args`: success, standard output, standard error.
fn run(args: &[&str]) -> (bool, String, String) {
    let out = enact_hub().args(args).output().expect("enact-hub runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The audit actions whose name starts with `prefix`, oldest first.
async fn actions(hub: &Hub, prefix: &str) -> Vec<String> {
    let mut entries = enact_hub::app::audit::list(
        hub,
        AuditFilter {
            action: Some(prefix.to_owned()),
            limit: 100,
            ..AuditFilter::default()
        },
    )
    .await
    .expect("audit");
    entries.reverse();
    entries.into_iter().map(|e| e.action).collect()
}

/// `annotator`'s queue as item ids, in queue order.
async fn queue_ids(hub: &Hub, annotator: i64) -> Vec<String> {
    annotation::queue(hub, annotator)
        .await
        .expect("queue")
        .into_iter()
        .map(|e| e.item_id)
        .collect()
}

/// Opens `item` of "mini" and submits `slots` as the answer; the two statuses.
async fn answer(browser: &mut Browser, csrf: &str, item: &str, slots: &[u8]) -> (u16, u16) {
    let page = browser.get(&format!("/annotate/mini/{item}")).await;
    let submitted = browser
        .post_json(
            &format!("/annotate/mini/{item}/submit"),
            Some(csrf),
            &json!({"slots": slots, "counts": {"placements": slots.len(), "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    (page.status().as_u16(), submitted.status().as_u16())
}

/// `path` as `browser`'s session would get it with the language switch set to Chinese.
async fn in_chinese(server: &TestServer, browser: &Browser, path: &str) -> String {
    server
        .call(Method::GET, path)
        .header(
            "cookie",
            &format!("{}; enact_lang=zh-CN", browser.cookie_header()),
        )
        .expect(200)
        .await
        .text
}

async fn draft_slots(server: &TestServer, annotator: i64, item: &str) -> Option<String> {
    db!(
        server.pool,
        fetch_optional,
        sqlx::query_scalar::<_, String>(
            "SELECT d.slots FROM drafts d JOIN items i ON i.id = d.item \
             WHERE d.annotator = $1 AND i.item_id = $2"
        )
        .bind(annotator)
        .bind(item)
    )
    .expect("draft read")
}

#[tokio::test]
async fn a_paused_queue_refuses_its_annotator_s_work_in_their_language_and_resuming_restores_it() {
    let (server, records, admin) = server_with_items().await;
    let hub = Hub::from(server.pool.clone());
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let alice = annotator(&server, "alice", false).await;
    let bob = annotator(&server, "bob", false).await;
    let items: Vec<String> = records.iter().take(4).map(id).collect();
    assign_listed(&hub, alice, &items).await;
    let (mut browser, csrf) = logged_in_on(&server, "alice", "/annotate").await;
    // A half-placed answer of the first item.
    assert_eq!(
        browser
            .get(&format!("/annotate/mini/{}", items[0]))
            .await
            .status(),
        200
    );
    let draft = json!({"slots": [2, null], "counts": {"placements": 1, "swaps": 0, "clears": 0, "undos": 0}});
    let saved = browser
        .post_json(
            &format!("/annotate/mini/{}/draft", items[0]),
            Some(&csrf),
            &draft,
        )
        .await;
    assert_eq!(saved.status(), 200);

    // Paused from the command line beside the running server: its next request sees it.
    let (ok, out, err) = run(&["annotator", "pause", "nobody", "--db", db]);
    assert!(
        !ok && err.contains("no annotator named 'nobody'"),
        "{out}{err}"
    );
    let (ok, out, err) = run(&["annotator", "pause", "alice", "--db", db]);
    assert!(ok && out.contains("queue paused"), "{out}{err}");
    let (_, html) = browser.text("/annotate").await;
    assert!(html.contains(r#"id="queue-paused""#), "{html}");
    assert!(html.contains("Your queue is paused by an admin"), "{html}");
    assert!(
        !html.contains(r#"id="continue""#),
        "no item to continue with: {html}"
    );
    let html = in_chinese(&server, &browser, "/annotate").await;
    assert!(html.contains("管理员已暂停您的队列"), "{html}");

    // Opening, saving, answering, skipping: refused with the reason.
    let page = browser.get(&format!("/annotate/mini/{}", items[1])).await;
    assert_eq!(page.status(), 409);
    assert!(page.text().await.expect("body").contains("paused"));
    let refused = browser
        .post_json(
            &format!("/annotate/mini/{}/draft", items[0]),
            Some(&csrf),
            &json!({"slots": [2, 1], "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(refused.status(), 409);
    let body: Value = refused.json().await.expect("JSON error");
    assert!(
        body["error"]
            .as_str()
            .expect("message")
            .contains("your queue is paused"),
        "{body}"
    );
    let (_, submitted) = answer(&mut browser, &csrf, &items[0], &[2, 1]).await;
    assert_eq!(submitted, 409);
    let skipped = browser
        .post_form(
            &format!("/annotate/mini/{}/skip", items[2]),
            &[("csrf", &csrf), ("action", "skip"), ("reason", "blurry")],
        )
        .await;
    assert_eq!(skipped.status(), 409);
    let next = browser.get("/annotate/next").await;
    assert_eq!(
        next.headers()["location"].to_str().expect("location"),
        "/annotate"
    );

    // No balanced split gives her items while paused; a split over her alone is refused.
    let assigned = annotation::assign(
        &hub,
        &tester(),
        "mini",
        &Assignment::Split(vec![alice, bob]),
    )
    .await
    .expect("split");
    assert_eq!(assigned.paused, ["alice"]);
    assert_eq!(queue_ids(&hub, alice).await, items, "alice got nothing new");
    assert_eq!(queue_ids(&hub, bob).await.len() as u64, assigned.added);
    let alone = annotation::assign(&hub, &tester(), "mini", &Assignment::Split(vec![alice])).await;
    assert!(matches!(
        alone,
        Err(enact_hub::app::AppError::Refused(
            enact_hub::app::refusal::Refusal::AllChosenPaused
        ))
    ));

    // The API: already paused changes nothing; DELETE resumes once.
    let path = "/api/v1/admin/annotators/alice/pause";
    let again = server
        .call(Method::PUT, path)
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(
        again,
        json!({"annotator": "alice", "paused": true, "changed": false})
    );
    let resumed = server
        .call(Method::DELETE, path)
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(resumed["changed"], true);
    let noop = server
        .call(Method::DELETE, path)
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(noop["changed"], false);
    server
        .call(Method::PUT, "/api/v1/admin/annotators/nobody/pause")
        .bearer(&admin)
        .expect(404)
        .await;

    // Resumed as it was: the draft is there, and the work goes on.
    assert_eq!(
        draft_slots(&server, alice, &items[0]).await.as_deref(),
        Some("[2,null]")
    );
    let (_, html) = browser.text("/annotate").await;
    assert!(!html.contains(r#"id="queue-paused""#), "{html}");
    let (opened, submitted) = answer(&mut browser, &csrf, &items[0], &[2, 1]).await;
    assert_eq!((opened, submitted), (200, 200));

    // The admin page's buttons pause and resume too.
    annotator(&server, "lead", true).await;
    let (mut lead, lead_csrf) = logged_in_on(&server, "lead", "/admin").await;
    let (status, html) = lead.text("/admin/quality?dataset=mini").await;
    assert_eq!(status, 200);
    assert!(html.contains("Pause alice"), "{html}");
    let paused = lead
        .post_form(
            "/admin/quality/pause",
            &[
                ("csrf", &lead_csrf),
                ("dataset", "mini"),
                ("annotator", "alice"),
                ("action", "pause"),
            ],
        )
        .await;
    assert_eq!(paused.status(), 200);
    let html = paused.text().await.expect("page");
    assert!(
        html.contains("Resume alice") && html.contains("paused by annotator lead"),
        "{html}"
    );
    let resumed = lead
        .post_form(
            "/admin/quality/pause",
            &[
                ("csrf", &lead_csrf),
                ("dataset", "mini"),
                ("annotator", "alice"),
                ("action", "resume"),
            ],
        )
        .await;
    assert!(resumed.text().await.expect("page").contains("Pause alice"));
    let (ok, out, _) = run(&["annotator", "resume", "alice", "--db", db]);
    assert!(ok && out.contains("was not paused"), "{out}");

    assert_eq!(
        actions(&hub, "annotator").await,
        [
            "annotator.pause",
            "annotator.resume",
            "annotator.pause",
            "annotator.resume"
        ]
    );
    server.stop().await;
}

#[tokio::test]
async fn a_handover_moves_exactly_the_unfinished_items_evenly_and_keeps_finished_answers() {
    let (server, records, admin) = server_with_items().await;
    let hub = Hub::from(server.pool.clone());
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let alice = annotator(&server, "alice", false).await;
    let bob = annotator(&server, "bob", false).await;
    let carol = annotator(&server, "carol", false).await;
    let dave = annotator(&server, "dave", false).await;
    // An admin and a paused annotator are no default recipients.
    annotator(&server, "lead", true).await;
    enact_hub::app::controls::pause(&hub, &tester(), "dave")
        .await
        .expect("paused");
    let items: Vec<String> = records.iter().take(10).map(id).collect();
    assign_listed(&hub, alice, &items).await;
    // Bob has two of alice's unfinished items already, dave one.
    assign_listed(&hub, bob, &items[5..7]).await;
    assign_listed(&hub, dave, &items[9..10]).await;
    let (mut browser, csrf) = logged_in_on(&server, "alice", "/annotate").await;
    for item in &items[..3] {
        let truth = labels(&records.iter().find(|r| id(r) == *item).expect("record")["gt_answer"]);
        assert_eq!(answer(&mut browser, &csrf, item, &truth).await, (200, 200));
    }
    assert_eq!(
        browser
            .get(&format!("/annotate/mini/{}", items[3]))
            .await
            .status(),
        200
    );

    // Refusals name what was wrong.
    let handover = "/api/v1/admin/annotators/alice/handover";
    let to_self = server
        .call(Method::POST, handover)
        .bearer(&admin)
        .json(&json!({"to": ["alice"]}))
        .expect(400)
        .await;
    assert!(to_self.error().contains("themselves"), "{}", to_self.text);
    assert_eq!(
        to_self.json()["code"],
        "handover_to_self",
        "{}",
        to_self.text
    );
    assert_eq!(to_self.json()["details"]["annotator"], "alice");
    server
        .call(Method::POST, handover)
        .bearer(&admin)
        .json(&json!({"to": ["nobody"]}))
        .expect(404)
        .await;
    let to_paused = server
        .call(Method::POST, handover)
        .bearer(&admin)
        .json(&json!({"to": ["dave"]}))
        .expect(409)
        .await;
    assert!(to_paused.error().contains("paused"), "{}", to_paused.text);
    assert_eq!(
        to_paused.json()["code"],
        "recipient_paused",
        "{}",
        to_paused.text
    );
    assert_eq!(to_paused.json()["details"]["annotator"], "dave");

    // Without names: bob and carol (not the admin, not paused dave).
    let done = server
        .call(Method::POST, handover)
        .bearer(&admin)
        .json(&json!({}))
        .expect(200)
        .await
        .json();
    let got = |who: &str| -> Vec<String> {
        done["to"]
            .as_array()
            .expect("to")
            .iter()
            .find(|t| t["annotator"] == who)
            .unwrap_or_else(|| panic!("{who} in {done}"))["items"]
            .as_array()
            .expect("items")
            .iter()
            .map(|i| i["item_id"].as_str().expect("id").to_owned())
            .collect()
    };
    let (to_bob, to_carol) = (got("bob"), got("carol"));
    assert_eq!(done["to"].as_array().expect("to").len(), 2, "{done}");
    let mut moved: Vec<String> = to_bob.iter().chain(&to_carol).cloned().collect();
    moved.sort();
    let mut unfinished = items[3..].to_vec();
    unfinished.sort();
    assert_eq!(
        moved, unfinished,
        "exactly the unfinished items move: {done}"
    );
    assert!(to_bob.len().abs_diff(to_carol.len()) <= 1, "{done}");
    assert!(
        !to_bob.iter().any(|i| items[5..7].contains(i)),
        "bob had those already: {done}"
    );
    assert_eq!(done["drafts_removed"], 1, "{done}");
    assert_eq!(done["kept"], json!([]));

    // Alice keeps her finished answers and nothing else; her draft is gone.
    assert_eq!(queue_ids(&hub, alice).await, items[..3]);
    assert_eq!(draft_slots(&server, alice, &items[3]).await, None);
    let finished: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT count(*) FROM annotations WHERE annotator = $1").bind(alice)
    )
    .expect("count");
    assert_eq!(finished, 3);
    let bob_queue: HashSet<String> = queue_ids(&hub, bob).await.into_iter().collect();
    assert!(to_bob.iter().all(|i| bob_queue.contains(i)));
    assert_eq!(bob_queue.len(), 2 + to_bob.len());
    let carol_queue: HashSet<String> = queue_ids(&hub, carol).await.into_iter().collect();
    assert_eq!(carol_queue, to_carol.iter().cloned().collect());
    // An item moved away is no longer hers: opening it is 403.
    assert_eq!(
        browser
            .get(&format!("/annotate/mini/{}", items[3]))
            .await
            .status(),
        403
    );

    // The command line: bob's unfinished items to carol; the ones carol has stay with bob.
    let (ok, out, err) = run(&[
        "annotator",
        "handover",
        "bob",
        "--to",
        "carol",
        "--db",
        db,
        "--json",
    ]);
    assert!(ok, "{out}{err}");
    let cli: Value = serde_json::from_str(&out).expect("JSON");
    let stayed: HashSet<String> = cli["kept"]
        .as_array()
        .expect("kept")
        .iter()
        .map(|i| i["item_id"].as_str().expect("id").to_owned())
        .collect();
    let carol_had: HashSet<String> = bob_queue.intersection(&carol_queue).cloned().collect();
    assert_eq!(stayed, carol_had, "{cli}");
    assert_eq!(
        cli["to"][0]["items"].as_array().expect("items").len(),
        bob_queue.len() - carol_had.len(),
        "{cli}"
    );
    let (ok, _, err) = run(&["annotator", "handover", "alice", "--to", "dave", "--db", db]);
    assert!(!ok && err.contains("paused"), "{err}");

    // The page's form.
    let (mut lead, lead_csrf) = logged_in_on(&server, "lead", "/admin").await;
    let page = lead
        .post_form(
            "/admin/quality/handover",
            &[
                ("csrf", &lead_csrf),
                ("dataset", "mini"),
                ("annotator", "carol"),
                ("to", "alice"),
            ],
        )
        .await;
    assert_eq!(page.status(), 200);
    let html = page.text().await.expect("page");
    assert!(
        html.contains("Unfinished items of &#39;carol&#39; handed over"),
        "{html}"
    );
    assert_eq!(
        actions(&hub, "annotator.handover").await.len(),
        3,
        "one entry per handover"
    );
    server.stop().await;
}

#[tokio::test]
async fn attention_checks_are_mixed_in_judged_counted_and_kept_out_of_the_human_row_and_agreement()
{
    let (server, records, admin) = server_with_items().await;
    let hub = Hub::from(server.pool.clone());
    let gts: BTreeMap<String, Vec<u8>> = records
        .iter()
        .map(|r| (id(r), labels(&r["gt_answer"])))
        .collect();
    // A forward L = 3 item told "reverse" (expects [2, 1]), an inverse one told "keep" ([1, 2]).
    let (reverse, keep) = (id(&records[0]), id(&records[6]));
    let expected: BTreeMap<String, Vec<u8>> =
        [(reverse.clone(), vec![2, 1]), (keep.clone(), vec![1, 2])].into();
    let path = "/api/v1/admin/datasets/mini/attention";
    let unknown = server
        .call(Method::PUT, path)
        .bearer(&admin)
        .json(&json!({"rate": 3, "checks": [{"item_id": "nope", "instruction": "keep"}]}))
        .expect(400)
        .await;
    assert!(unknown.error().contains("nope"), "{}", unknown.text);
    let twice = server
        .call(Method::PUT, path)
        .bearer(&admin)
        .json(&json!({"rate": 3, "checks": [
            {"item_id": reverse, "instruction": "keep"},
            {"item_id": reverse, "instruction": "reverse"}
        ]}))
        .expect(400)
        .await;
    assert_eq!(twice.json()["code"], "listed_twice", "{}", twice.text);
    assert_eq!(
        twice.json()["details"],
        json!({"field": "checks", "item": reverse})
    );
    server
        .call(Method::PUT, path)
        .bearer(&admin)
        .json(&json!({"rate": 3, "checks": [{"item_id": reverse, "instruction": "sideways"}]}))
        .expect(422)
        .await;
    let set = server
        .call(Method::PUT, path)
        .bearer(&admin)
        .json(&json!({"rate": 3, "checks": [
            {"item_id": reverse, "instruction": "reverse"},
            {"item_id": keep, "instruction": "keep"},
        ]}))
        .expect(200)
        .await
        .json();
    assert_eq!(set["attention"]["rate"], 3, "{set}");
    assert_eq!(
        set["attention"]["checks"].as_array().expect("checks").len(),
        2
    );

    // Eight ordinary items each: one check after every two, at most the two there are.
    let ordinary: Vec<String> = records[12..20].iter().map(id).collect();
    let careful = annotator(&server, "careful", false).await;
    let careless = annotator(&server, "careless", false).await;
    let late = annotator(&server, "late", false).await;
    for who in [careful, careless] {
        assign_listed(&hub, who, &ordinary).await;
    }
    assign_listed(&hub, late, &ordinary[..4]).await;
    for who in [careful, careless, late] {
        let queue = queue_ids(&hub, who).await;
        assert!(
            queue.contains(&reverse) && queue.contains(&keep),
            "{who}: {queue:?}"
        );
    }
    let queue = queue_ids(&hub, careful).await;
    let first_check = queue
        .iter()
        .position(|i| expected.contains_key(i))
        .expect("a check");
    assert_eq!(first_check, 2, "after two ordinary items: {queue:?}");

    // The item page shows the instruction in the annotator's language.
    let (mut browser, _) = logged_in_on(&server, "late", "/annotate").await;
    let (_, html) = browser.text(&format!("/annotate/mini/{reverse}")).await;
    assert!(html.contains(r#"id="attention-instruction""#), "{html}");
    assert!(html.contains("put the frames in reverse order"), "{html}");
    let (_, html) = browser.text(&format!("/annotate/mini/{keep}")).await;
    assert!(html.contains("in the order they are listed"), "{html}");
    let (_, html) = browser
        .text(&format!("/annotate/mini/{}", ordinary[0]))
        .await;
    assert!(!html.contains("attention-instruction"), "{html}");
    let html = in_chinese(&server, &browser, &format!("/annotate/mini/{reverse}")).await;
    assert!(html.contains("注意力检查"), "{html}");

    // Careful follows the instructions; careless answers the opposite order.
    work_queue(
        &server,
        "careful",
        careful,
        |_| 20,
        |item| expected.get(item).unwrap_or(&gts[item]).clone(),
    )
    .await;
    work_queue(
        &server,
        "careless",
        careless,
        |_| 20,
        |item| match expected.get(item) {
            Some(e) => e.iter().rev().copied().collect(),
            None => gts[item].clone(),
        },
    )
    .await;

    let report = server
        .call(Method::GET, "/api/v1/admin/annotators/quality?dataset=mini")
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(report["attention_checks"], 2, "{report}");
    let checks: BTreeMap<String, (u64, u64, u64)> = report["attention"]
        .as_array()
        .expect("attention")
        .iter()
        .map(|c| {
            let n = |k: &str| c[k].as_u64().expect("a count");
            (
                c["annotator"].as_str().expect("name").to_owned(),
                (n("passed"), n("failed"), n("pending")),
            )
        })
        .collect();
    assert_eq!(
        checks,
        BTreeMap::from([
            ("careful".to_owned(), (2, 0, 0)),
            ("careless".to_owned(), (0, 2, 0)),
            ("late".to_owned(), (0, 0, 2)),
        ])
    );
    // The checks are no answers to the scene: out of the figures and of agreement.
    for a in report["annotators"].as_array().expect("annotators") {
        assert_eq!(a["items_done"], 8, "{a}");
        assert_eq!(a["shared_items"], 8, "{a}");
        assert_eq!(a["exact_agreement"], 1.0, "{a}");
    }
    let board = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .expect(200)
        .await
        .json();
    let human = board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|r| r["source"] == "human")
        .expect("a Human row")
        .clone();
    assert_eq!(human["human"]["answers"], 16, "{human}");
    assert_eq!(human["human"]["dataset_items"], 22, "{human}");
    assert_eq!(human["overall"]["task_accuracy"], 1.0, "{human}");

    // The page counts them too.
    annotator(&server, "lead", true).await;
    let (mut lead, lead_csrf) = logged_in_on(&server, "lead", "/admin").await;
    let (_, html) = lead.text("/admin/quality?dataset=mini").await;
    assert!(html.contains(r#"id="attention-checks""#), "{html}");
    assert!(
        html.contains("<th scope=\"row\">careless</th><td>0</td><td>2</td><td>0</td>"),
        "{html}"
    );
    assert!(html.contains(&format!("{reverse} reverse")), "{html}");

    // Clearing takes late's pending checks out; given answers stay.
    let cleared = server
        .call(Method::DELETE, path)
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(cleared, json!({"cleared": true, "removed": 2}));
    assert_eq!(queue_ids(&hub, late).await.len(), 4);
    let shown = server
        .call(Method::GET, path)
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(shown["attention"], Value::Null);
    // Set again from the page's form.
    let page = lead
        .post_form(
            "/admin/quality/attention",
            &[
                ("csrf", &lead_csrf),
                ("dataset", "mini"),
                ("rate", "5"),
                ("checks", &format!("{reverse} reverse\n")),
            ],
        )
        .await;
    assert_eq!(page.status(), 200);
    assert!(
        page.text()
            .await
            .expect("page")
            .contains("1 items, one in every 5")
    );
    assert_eq!(
        actions(&hub, "attention").await,
        ["attention.set", "attention.clear", "attention.set"]
    );
    server.stop().await;
}

#[tokio::test]
async fn the_command_line_sets_shows_and_clears_attention_checks() {
    let (server, records, _) = server_with_items().await;
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let list = server.dir().join("checks.txt");
    std::fs::write(
        &list,
        format!(
            "# checks\n{} reverse\n{} keep\n",
            id(&records[0]),
            id(&records[7])
        ),
    )
    .expect("list written");
    let list = list.to_str().expect("utf-8 path");
    let bad = server.dir().join("bad.txt");
    std::fs::write(&bad, format!("{} upside-down\n", id(&records[0]))).expect("written");
    let (ok, _, err) = run(&[
        "attention",
        "set",
        "mini",
        "--db",
        db,
        "--checks",
        bad.to_str().expect("path"),
        "--rate",
        "5",
    ]);
    assert!(!ok && err.contains("line 1"), "{err}");
    let (ok, out, err) = run(&[
        "attention",
        "set",
        "mini",
        "--db",
        db,
        "--checks",
        list,
        "--rate",
        "5",
    ]);
    assert!(
        ok && out.contains("2 attention checks, one in every 5"),
        "{out}{err}"
    );
    let (ok, out, _) = run(&["attention", "show", "mini", "--db", db]);
    assert!(
        ok && out.contains(&format!("{} keep", id(&records[7]))),
        "{out}"
    );
    let (ok, out, _) = run(&["attention", "clear", "mini", "--db", db]);
    assert!(ok && out.contains("attention checks cleared"), "{out}");
    let (ok, out, _) = run(&["attention", "show", "mini", "--db", db]);
    assert!(ok && out.contains("has no attention checks"), "{out}");
    server.stop().await;
}
