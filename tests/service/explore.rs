//! The explorer: `GET /api/v1/datasets/{d}/explore` (JSON and CSV) and the page
//! `/datasets/{d}/explore`, on a hand-made dataset whose every filter's items are known here.

use std::collections::BTreeSet;

use enact_hub::app::Hub;
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use reqwest::Method;
use serde_json::{Value, json};

use crate::annotate::{annotator, logged_in_on};
use crate::compare::server_with_two_activities;
use crate::helpers::*;
use crate::quality::{assign_listed, work_queue};

fn id(records: &[Value], i: usize) -> String {
    records[i]["id"].as_str().expect("id").to_owned()
}

fn ids(records: &[Value], at: &[usize]) -> Vec<String> {
    at.iter().map(|&i| id(records, i)).collect()
}

fn set(records: &[Value], at: &[usize]) -> BTreeSet<String> {
    ids(records, at).into_iter().collect()
}

/// The items of a page, in order.
fn listed(page: &Value) -> Vec<String> {
    page["items"]
        .as_array()
        .unwrap_or_else(|| panic!("items: {page}"))
        .iter()
        .map(|i| i["id"].as_str().expect("id").to_owned())
        .collect()
}

async fn explore(server: &TestServer, query: &str) -> Value {
    let (status, page) = server
        .get_json(&format!(
            "/api/v1/datasets/mini/explore?{query}&per_page=500"
        ))
        .await;
    assert_eq!(status, 200, "{query}: {page}");
    page
}

/// The items a view shows, whatever their order.
async fn shown(server: &TestServer, query: &str) -> BTreeSet<String> {
    listed(&explore(server, query).await).into_iter().collect()
}

#[tokio::test]
async fn every_filter_pattern_sort_and_count_of_the_explorer() {
    let (server, records) = server_with_two_activities().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    let (_, admin_token) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    // Alpha is wrong on 0, 1, 2 and 9. Beta is wrong on 3–7 and 9, and its reply to 10 cannot
    // be read.
    let alpha = submit_to(
        &server,
        "mini",
        "model=Alpha",
        &alice,
        answers(&records, &[0, 1, 2, 9]),
    )
    .await;
    assert_eq!(alpha.status, 201, "{}", alpha.text);
    let unreadable = id(&records, 10);
    let beta_body: String = answers(&records, &[3, 4, 5, 6, 7, 9])
        .lines()
        .map(|line| {
            let mut record: Value = serde_json::from_str(line).expect("line");
            if record["id"] == unreadable.as_str() {
                record["answer"] = json!("I cannot tell");
            }
            record.to_string() + "\n"
        })
        .collect();
    let beta = submit_to(&server, "mini", "model=Beta", &bob, beta_body).await;
    assert_eq!(beta.status, 201, "{}", beta.text);
    let (a, b) = (alpha.id(), beta.id());

    // Two annotators: "ann-a" answers items 3 and 9 with the truth, "ann-b" item 9 reversed.
    let hub = Hub::from(server.pool.clone());
    let ann_a = annotator(&server, "ann-a", false).await;
    let ann_b = annotator(&server, "ann-b", false).await;
    assign_listed(&hub, ann_a, &ids(&records, &[3, 9])).await;
    assign_listed(&hub, ann_b, &ids(&records, &[9])).await;
    let truth = |item: &str| -> Vec<u8> {
        let record = records.iter().find(|r| r["id"] == item).expect("record");
        record["gt_answer"]
            .as_array()
            .expect("gt")
            .iter()
            .map(|v| u8::try_from(v.as_u64().expect("label")).expect("small"))
            .collect()
    };
    work_queue(&server, "ann-a", ann_a, |_| 30, truth).await;
    work_queue(
        &server,
        "ann-b",
        ann_b,
        |_| 30,
        |item| {
            let mut order = truth(item);
            order.reverse();
            order
        },
    )
    .await;

    // Hidden answers (the default): nobody but an admin sees the explorer.
    let (status, body) = server.get_json("/api/v1/datasets/mini/explore").await;
    assert_eq!(status, 404, "{body}");
    assert!(
        body["error"].as_str().expect("error").contains("hidden"),
        "{body}"
    );
    assert_eq!(server.get("/datasets/mini/explore").await.status(), 404);
    // An admin's API token sees it; a submitter's does not.
    server
        .call(Method::GET, "/api/v1/datasets/mini/explore")
        .bearer(&admin_token)
        .expect(200)
        .await;
    server
        .call(Method::GET, "/api/v1/datasets/mini/explore")
        .bearer(&alice)
        .expect(404)
        .await;
    annotator(&server, "boss", true).await;
    let (mut admin, _) = logged_in_on(&server, "boss", "/annotate").await;
    let page = admin.get("/datasets/mini/explore").await;
    assert_eq!(page.status(), 200);
    let api = admin.get("/api/v1/datasets/mini/explore").await;
    assert_eq!(api.status(), 200);
    let (mut someone, _) = logged_in_on(&server, "ann-a", "/annotate").await;
    assert_eq!(
        someone.get("/datasets/mini/explore").await.status(),
        404,
        "an annotator is no admin"
    );

    set_mini_answers(&server.pool, AnswerVisibility::Public).await;
    let all = explore(&server, "").await;
    // The rows: the board's, in its order (both tie on nothing: Alpha 8/12, Beta 5/12).
    let rows: Vec<i64> = all["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .map(|r| r["submission"].as_i64().expect("id"))
        .collect();
    assert_eq!(rows, [a, b], "{}", all["rows"]);
    assert_eq!(all["rows"][0]["model"], "Alpha");
    let column = |item: &Value, row: usize| item["verdicts"][row].as_str().map(str::to_owned);
    let item_of = |page: &Value, i: usize| -> Value {
        page["items"]
            .as_array()
            .expect("items")
            .iter()
            .find(|x| x["id"] == id(&records, i).as_str())
            .unwrap_or_else(|| panic!("item {i} in {page}"))
            .clone()
    };
    let item9 = item_of(&all, 9);
    assert_eq!(column(&item9, 0).as_deref(), Some("wrong"));
    assert_eq!(column(&item9, 1).as_deref(), Some("wrong"));
    // One right and one wrong answer: a tie is no majority.
    assert_eq!(
        item9["human"],
        json!({"verdict": "wrong", "answers": 2, "right": 1, "exact": 1}),
        "{item9}"
    );
    let item10 = item_of(&all, 10);
    assert_eq!(column(&item10, 1).as_deref(), Some("unparseable"));
    assert_eq!(item10["human"]["verdict"], "missing");
    let item3 = item_of(&all, 3);
    assert_eq!(item3["human"]["verdict"], "exact");
    assert_eq!(
        (item3["rows_wrong"].as_u64(), item3["rows_judged"].as_u64()),
        (Some(1), Some(3))
    );

    // Hardest first: 9 (every row wrong), the items half the rows get wrong in the dataset's
    // order, 3 (one of three), then 8 and 11 (none).
    assert_eq!(
        listed(&all),
        ids(&records, &[9, 0, 1, 2, 4, 5, 6, 7, 10, 3, 8, 11])
    );

    // Each filter.
    assert_eq!(
        shown(&server, "direction=inverse").await,
        set(&records, &[3, 4, 5, 9, 10, 11])
    );
    assert_eq!(
        shown(&server, "step_length=3").await,
        set(&records, &[0, 3, 6, 9])
    );
    assert_eq!(
        shown(&server, "activity=wash_dishes").await,
        set(&records, &[6, 7, 8, 9, 10, 11])
    );
    assert_eq!(
        shown(&server, "pattern=models-disagree").await,
        set(&records, &[0, 1, 2, 3, 4, 5, 6, 7, 10])
    );
    assert_eq!(
        shown(&server, "pattern=unparseable").await,
        set(&records, &[10])
    );
    assert_eq!(
        shown(&server, &format!("pattern=only:{a}")).await,
        set(&records, &[3, 4, 5, 6, 7, 10])
    );
    assert_eq!(
        shown(&server, &format!("pattern=only:{b}")).await,
        set(&records, &[0, 1, 2])
    );
    assert!(
        shown(&server, "pattern=humans-right-models-wrong")
            .await
            .is_empty(),
        "item 9's Human cell is a tie"
    );
    assert_eq!(
        shown(
            &server,
            "direction=forward&activity=cook_bacon&pattern=models-disagree"
        )
        .await,
        set(&records, &[0, 1, 2])
    );

    // Counts per filter, the other filters kept.
    let view = explore(&server, "direction=forward&pattern=models-disagree").await;
    let c = &view["counts"];
    assert_eq!(
        (c["items"].as_u64(), c["matching"].as_u64()),
        (Some(12), Some(5))
    );
    assert_eq!(
        c["directions"],
        json!([{"value": "forward", "items": 5}, {"value": "inverse", "items": 4}])
    );
    assert_eq!(
        c["step_lengths"],
        json!([{"value": 3, "items": 2}, {"value": 4, "items": 2}, {"value": 5, "items": 1}])
    );
    assert_eq!(
        c["activities"],
        json!([{"value": "cook_bacon", "items": 3}, {"value": "wash_dishes", "items": 2}])
    );
    let p = &c["patterns"];
    assert_eq!(p["any"], 6, "{p}");
    assert_eq!(p["models_disagree"], 5, "{p}");
    assert_eq!(p["humans_right_models_wrong"], 0, "{p}");
    assert_eq!(p["unparseable"], 0, "{p}");
    assert_eq!(
        p["only_right"],
        json!([{"value": a, "items": 2}, {"value": b, "items": 3}])
    );
    // Right answers among the five: Alpha on 6 and 7, Beta on 0, 1, 2; no human verdict.
    assert_eq!(c["right"], json!([2, 3, 0]));
    assert_eq!(
        view["view"],
        json!({"direction": "forward", "pattern": "models-disagree"})
    );

    // Sorting by a row.
    let wrong_first = listed(&explore(&server, &format!("sort=wrong:{a}")).await);
    assert_eq!(wrong_first[..4], ids(&records, &[0, 1, 2, 9]));
    let right_first = listed(&explore(&server, &format!("sort=right:{b}")).await);
    assert_eq!(right_first[..5], ids(&records, &[0, 1, 2, 8, 11]));
    let human_first = listed(&explore(&server, "sort=right:human").await);
    assert_eq!(human_first[..2], ids(&records, &[3, 9]));
    assert_eq!(human_first[0], id(&records, 3), "right before wrong");

    // Pages.
    let (_, first) = server
        .get_json("/api/v1/datasets/mini/explore?per_page=5")
        .await;
    assert_eq!(
        (first["page"].as_u64(), first["pages"].as_u64()),
        (Some(1), Some(3))
    );
    assert_eq!(listed(&first), ids(&records, &[9, 0, 1, 2, 4]));
    let (_, last) = server
        .get_json("/api/v1/datasets/mini/explore?per_page=5&page=3")
        .await;
    assert_eq!(listed(&last), ids(&records, &[8, 11]));

    // Views that name nothing the dataset has are refused, naming the parameter.
    for (query, named) in [
        ("direction=up", "direction"),
        ("step_length=12", "step_length"),
        ("activity=juggling", "activity"),
        ("pattern=everyone", "pattern"),
        ("pattern=only:999999", "pattern"),
        ("sort=wrong:999999", "sort"),
        ("page=0", "page"),
        ("format=xml", "format"),
    ] {
        let reply = server
            .call(
                Method::GET,
                &format!("/api/v1/datasets/mini/explore?{query}"),
            )
            .expect(400)
            .await;
        assert!(reply.error().contains(named), "{query}: {}", reply.text);
    }

    // Excluding ann-b leaves ann-a's right answer on item 9: humans right, every model wrong.
    server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/exclusions/ann-b")
        .bearer(&admin_token)
        .expect(200)
        .await;
    assert_eq!(
        shown(&server, "pattern=humans-right-models-wrong").await,
        set(&records, &[9])
    );
    let item9 = item_of(&explore(&server, "").await, 9);
    assert_eq!(item9["human"]["answers"], 1, "{item9}");
    // A new answer shows at once: "ann-c" answers item 11 with the truth.
    let ann_c = annotator(&server, "ann-c", false).await;
    assign_listed(&hub, ann_c, &ids(&records, &[11])).await;
    work_queue(&server, "ann-c", ann_c, |_| 30, truth).await;
    let item11 = item_of(&explore(&server, "").await, 11);
    assert_eq!(
        item11["human"],
        json!({"verdict": "exact", "answers": 1, "right": 1, "exact": 1}),
        "{item11}"
    );

    // CSV: every matching item, in the view's order, with a column per row.
    let csv = server
        .call(
            Method::GET,
            &format!("/api/v1/datasets/mini/explore?pattern=only:{b}&format=csv&per_page=1"),
        )
        .expect(200)
        .await;
    assert!(
        csv.headers["content-type"]
            .to_str()
            .expect("type")
            .starts_with("text/csv"),
        "{:?}",
        csv.headers
    );
    assert!(
        csv.headers["content-disposition"]
            .to_str()
            .expect("disposition")
            .contains("enact-hub-explore-mini.csv")
    );
    let lines: Vec<&str> = csv.text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(
        lines[0],
        format!(
            "item,direction,step_length,activity,rows_wrong,rows_judged,Alpha (#{a}),Beta (#{b}),\
             human,human_right,human_answers"
        )
    );
    assert_eq!(lines.len(), 4, "{}", csv.text);
    assert_eq!(
        lines[1],
        format!(
            "{},forward,3,cook_bacon,1,2,wrong,exact,missing,0,0",
            id(&records, 0)
        )
    );
    assert!(
        csv.text.contains(&format!("# view: pattern=only:{b}")),
        "{}",
        csv.text
    );

    // The page: the same grid, in both languages, each item linked to its page, and a
    // permalink of the view.
    let path = format!("/datasets/mini/explore?pattern=only:{b}&sort=wrong:{a}");
    let (status, html) = server.page_in(&path, "en").await;
    assert_eq!(status, 200, "{html}");
    for shown in [
        "<caption",
        "scope=\"col\"",
        "scope=\"row\"",
        "Humans right, every model wrong (1)",
        "Models disagree (9)",
        &format!("Only Alpha (#{a}) right (6)"),
        "Items matching: 3 of 12.",
        &format!("href=\"/datasets/mini/items/{}\"", id(&records, 0)),
        &format!("href=\"/datasets/mini/explore?pattern=only%3A{b}&#38;sort=wrong%3A{a}\""),
        "format=csv",
        "verdict-wrong",
        "verdict-exact",
        "verdict-missing",
    ] {
        assert!(html.contains(shown), "{shown} on the page:\n{html}");
    }
    // Item 10 is Beta's unparseable one: not among only-Beta-right items.
    assert!(!html.contains(&id(&records, 10)), "{html}");
    let (status, html) = server.page_in(&path, "zh-CN").await;
    assert_eq!(status, 200);
    for shown in ["人类答对、所有模型答错", "完全正确", "人类"] {
        assert!(html.contains(shown), "{shown} on the page:\n{html}");
    }
    // The leaderboard links to it.
    let (_, board) = server.page_in("/leaderboard/mini", "en").await;
    assert!(board.contains("/datasets/mini/explore"), "{board}");

    // Hidden again: the admin still sees the page, nobody else.
    set_mini_answers(&server.pool, AnswerVisibility::Hidden).await;
    assert_eq!(server.get(&path).await.status(), 404);
    assert_eq!(admin.get(&path).await.status(), 200);
    server.stop().await;
}
