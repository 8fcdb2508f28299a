//! One item, every answer: `GET /api/v1/datasets/{d}/items/{id}/answers` and the item page's
//! answers, with each verdict and, for wrong answers, the verifier's reasons.

use enact_hub::app::Hub;
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use serde_json::{Value, json};

use crate::annotate::{annotator, logged_in_on};
use crate::helpers::*;
use crate::quality::{assign_listed, work_queue};

fn labels(value: &Value) -> Vec<u8> {
    value
        .as_array()
        .unwrap_or_else(|| panic!("labels: {value}"))
        .iter()
        .map(|v| u8::try_from(v.as_u64().expect("label")).expect("small"))
        .collect()
}

#[tokio::test]
async fn an_item_shows_every_rows_and_every_annotators_answer_with_its_verdict_and_why() {
    // "mini": forward L=3, inverse L=3, forward L=4, inverse L=4. Item 1 is the inverse L=3
    // one, whose actions give it state changes (the verifier's table from the action text).
    let (server, records) = spawn_app_with_release().await;
    let item = records[1]["id"].as_str().expect("id").to_owned();
    let truth = labels(&records[1]["gt_answer"]);
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    let alpha = submit_to(
        &server,
        "mini",
        "model=Alpha",
        &alice,
        answers(&records, &[1]),
    )
    .await;
    assert_eq!(alpha.status, 201, "{}", alpha.text);
    // Beta's reply to item 1 cannot be read; its other answers are right.
    let beta_body: String = answers(&records, &[])
        .lines()
        .map(|line| {
            let mut record: Value = serde_json::from_str(line).expect("line");
            if record["id"] == item.as_str() {
                record["answer"] = json!("I cannot tell");
            }
            record.to_string() + "\n"
        })
        .collect();
    let beta = submit_to(&server, "mini", "model=Beta", &bob, beta_body).await;
    assert_eq!(beta.status, 201, "{}", beta.text);
    // Two annotators answer the item: one the truth, one the reverse.
    let hub = Hub::from(server.pool.clone());
    let right = annotator(&server, "ann-right", false).await;
    let wrong = annotator(&server, "ann-wrong", false).await;
    for who in [right, wrong] {
        assign_listed(&hub, who, std::slice::from_ref(&item)).await;
    }
    let reversed: Vec<u8> = truth.iter().rev().copied().collect();
    work_queue(&server, "ann-right", right, |_| 30, |_| truth.clone()).await;
    work_queue(&server, "ann-wrong", wrong, |_| 30, |_| reversed.clone()).await;

    // Hidden answers: nobody but an admin sees them.
    let path = format!("/api/v1/datasets/mini/items/{item}/answers");
    let (status, body) = server.get_json(&path).await;
    assert_eq!(status, 404, "{body}");
    assert!(
        body["error"].as_str().expect("error").contains("hidden"),
        "{body}"
    );
    let page = server.get(&format!("/datasets/mini/items/{item}")).await;
    let html = page.text().await.expect("page");
    assert!(
        html.contains("shown to admins only") && !html.contains("ann-right"),
        "{html}"
    );
    // An API client holding an admin token sees them, with names; a submitter's token does not.
    let (_, root) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let hidden = server
        .call(reqwest::Method::GET, &path)
        .bearer(&root)
        .expect(200)
        .await
        .json();
    assert_eq!(hidden["item"]["id"], item.as_str(), "{hidden}");
    assert!(hidden.to_string().contains("ann-right"), "{hidden}");
    server
        .call(reqwest::Method::GET, &path)
        .bearer(&alice)
        .expect(404)
        .await;

    set_mini_answers(&server.pool, AnswerVisibility::Public).await;
    let (status, a) = server.get_json(&path).await;
    assert_eq!(status, 200, "{a}");
    assert_eq!(a["item"]["id"], item.as_str());
    assert_eq!(a["item"]["direction"], "inverse");
    assert_eq!(labels(&a["truth"]), truth);
    let models = a["models"].as_array().expect("models");
    assert_eq!(models.len(), 2, "{a}");
    let row = |model: &str| {
        models
            .iter()
            .find(|m| m["model"] == model)
            .unwrap_or_else(|| panic!("{model} in {a}"))
    };
    let alpha_answer = row("Alpha");
    assert_eq!(alpha_answer["submission"], alpha.id());
    assert_eq!(alpha_answer["verdict"], "wrong");
    assert_eq!(alpha_answer["task_correct"], false);
    assert_eq!(labels(&alpha_answer["parsed"]), reversed);
    let why = &alpha_answer["why"];
    assert_eq!(why["rejected_steps"], 2, "{why}");
    assert_eq!(
        why["pairs_out_of_order"],
        json!([[truth[0], truth[1]]]),
        "{why}"
    );
    let step = &why["steps"][0];
    assert_eq!(step["accepted"], false);
    assert!(
        !step["implied"].as_array().expect("implied").is_empty()
            && !step["missed"].as_array().expect("missed").is_empty(),
        "{step}"
    );
    let beta_answer = row("Beta");
    assert_eq!(beta_answer["verdict"], "unparseable");
    assert_eq!(beta_answer["answer"], "\"I cannot tell\"");
    assert!(
        beta_answer["parsed"].is_null() && beta_answer["why"].is_null(),
        "{beta_answer}"
    );

    // Annotators, pseudonymous and in the order they answered; no exclusions or gold shown.
    let humans = a["humans"].as_array().expect("humans");
    assert_eq!(humans.len(), 2, "{a}");
    assert_eq!(humans[0]["annotator"], "annotator 1");
    assert_eq!(humans[0]["verdict"], "exact");
    assert!(humans[0]["why"].is_null());
    assert_eq!(humans[1]["annotator"], "annotator 2");
    assert_eq!(humans[1]["verdict"], "wrong");
    assert_eq!(humans[1]["why"]["rejected_steps"], 2);
    assert!(
        a.get("gold").is_none() && humans[0].get("excluded").is_none(),
        "{a}"
    );
    assert!(
        !a.to_string().contains("ann-right"),
        "no annotator name: {a}"
    );

    // The page shows the same, in both languages; an admin sees names.
    let page = format!("/datasets/mini/items/{item}");
    let (_, html) = server.page_in(&page, "en").await;
    for shown in [
        "Alpha (#",
        "Beta (#",
        "annotator 2",
        "Steps the verifier rejects",
    ] {
        assert!(html.contains(shown), "{shown} on the page");
    }
    assert!(
        html.contains("verdict-unparseable") && html.contains("verdict-exact"),
        "{html}"
    );
    let (_, html) = server.page_in(&page, "zh-CN").await;
    assert!(
        html.contains("验证器拒绝的步骤") && html.contains("无法解析"),
        "{html}"
    );

    annotator(&server, "boss", true).await;
    let (mut admin, _) = logged_in_on(&server, "boss", "/annotate").await;
    set_mini_answers(&server.pool, AnswerVisibility::Hidden).await;
    let html = admin.get(&page).await.text().await.expect("page");
    assert!(
        html.contains("ann-right") && html.contains("ann-wrong"),
        "{html}"
    );
    server.stop().await;
}
