//! Red flags an admin sees (`GET /api/v1/admin/datasets/{d}/flags` and its page), each on a
//! constructed case: a row above the humans on their items, a submission answering with the
//! ground truth, and items shared with a public dataset (also reported by the import).

use enact_hub::app::Hub;
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use enact_hub::store;
use reqwest::Method;
use serde_json::Value;

use crate::annotate::annotator;
use crate::compare::server_with_two_activities;
use crate::helpers::*;
use crate::quality::{assign_listed, work_queue};

fn models(list: &Value) -> Vec<&str> {
    let mut models: Vec<&str> = list
        .as_array()
        .unwrap_or_else(|| panic!("a list: {list}"))
        .iter()
        .map(|f| f["model"].as_str().expect("model"))
        .collect();
    models.sort_unstable();
    models
}

async fn set_answers(pool: &enact_hub::store::Pool, dataset: &str, answers: AnswerVisibility) {
    let mut tx = write_tx(pool).await;
    let d = store::datasets::by_name(&mut tx, dataset)
        .await
        .expect("query")
        .expect("dataset");
    store::submissions::set_answer_visibility(&mut tx, d.id, answers)
        .await
        .expect("set answers");
    tx.commit().await.expect("commit");
}

#[tokio::test]
async fn each_red_flag_on_a_constructed_case() {
    let (server, records) = server_with_two_activities().await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, lab) = api_token(&server.pool, "lab", Role::Submitter, None, None).await;
    let flags = |query: &'static str| {
        let server = &server;
        let admin = admin.clone();
        async move {
            server
                .call(
                    Method::GET,
                    &format!("/api/v1/admin/datasets/mini/flags{query}"),
                )
                .bearer(&admin)
                .expect(200)
                .await
                .json()
        }
    };
    let clean = flags("").await;
    assert_eq!(clean["answers"], "hidden");
    for kind in ["above_human", "identical_to_truth", "leaks"] {
        assert_eq!(clean[kind].as_array().map(Vec::len), Some(0), "{clean}");
    }

    // Twelve items. Copy gives the truth on all, Strong on ten (wrong on 0 and 9), Weak on
    // seven (wrong on 0–4).
    for (model, body) in [
        ("Copy", ground_truth_answers(&records)),
        ("Strong", answers(&records, &[0, 9])),
        ("Weak", answers(&records, &[0, 1, 2, 3, 4])),
    ] {
        let reply = submit_to(&server, "mini", &format!("model={model}"), &lab, body).await;
        assert_eq!(reply.status, 201, "{model}: {}", reply.text);
    }
    // One annotator answers items 0–5: 0–2 reversed (wrong), 3–5 right. The humans' task
    // accuracy on their six items is 0.5; Copy has 6/6, Strong 5/6, Weak 1/6 there.
    let hub = Hub::from(server.pool.clone());
    let ann = annotator(&server, "ann", false).await;
    let six: Vec<String> = records[..6]
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    assign_listed(&hub, ann, &six).await;
    let wrong_on: Vec<String> = six[..3].to_vec();
    work_queue(
        &server,
        "ann",
        ann,
        |_| 30,
        |item| {
            let record = records.iter().find(|r| r["id"] == item).expect("record");
            let mut order: Vec<u8> = record["gt_answer"]
                .as_array()
                .expect("gt")
                .iter()
                .map(|v| u8::try_from(v.as_u64().expect("label")).expect("small"))
                .collect();
            if wrong_on.iter().any(|w| w == item) {
                order.reverse();
            }
            order
        },
    )
    .await;

    let shown = flags("").await;
    assert_eq!(models(&shown["above_human"]), ["Copy", "Strong"], "{shown}");
    let strong = shown["above_human"]
        .as_array()
        .expect("list")
        .iter()
        .find(|f| f["model"] == "Strong")
        .expect("Strong");
    assert_eq!(strong["items"], 6, "{strong}");
    assert_eq!(strong["human_answers"], 6, "{strong}");
    assert!((strong["task_accuracy"].as_f64().expect("ta") - 5.0 / 6.0).abs() < 1e-9);
    assert!((strong["human_task_accuracy"].as_f64().expect("ta") - 0.5).abs() < 1e-9);
    // The truth on more than 90 % of the items: Copy alone (12/12); at 80 % Strong too (10/12).
    assert_eq!(models(&shown["identical_to_truth"]), ["Copy"], "{shown}");
    assert_eq!(shown["identical_to_truth"][0]["exact"], 12);
    assert_eq!(shown["identical_to_truth"][0]["items"], 12);
    let lower = flags("?share=0.8").await;
    assert_eq!(
        models(&lower["identical_to_truth"]),
        ["Copy", "Strong"],
        "{lower}"
    );
    let refused = server
        .call(Method::GET, "/api/v1/admin/datasets/mini/flags?share=1")
        .bearer(&admin)
        .expect(400)
        .await;
    assert!(refused.text.contains("share"), "{}", refused.text);
    server
        .call(Method::GET, "/api/v1/admin/datasets/mini/flags")
        .bearer(&lab)
        .expect(403)
        .await;
    server
        .call(Method::GET, "/api/v1/admin/datasets/mini/flags")
        .expect(401)
        .await;

    // The same release imported as "mirror": no leak while mirror's answers are hidden too.
    let root = server.dir().join("release");
    let mirrored = import(&server.pool, &root, &options("mirror")).await;
    assert!(mirrored.leaks.is_empty(), "{:?}", mirrored.leaks);
    assert!(
        flags("").await["leaks"]
            .as_array()
            .expect("leaks")
            .is_empty()
    );
    // Once mirror's answers are public, mini's twelve items and all their frames are out.
    set_answers(&server.pool, "mirror", AnswerVisibility::Public).await;
    let leaked = flags("").await;
    let leaks = leaked["leaks"].as_array().expect("leaks");
    assert_eq!(leaks.len(), 1, "{leaked}");
    assert_eq!(leaks[0]["dataset"], "mirror");
    assert_eq!(leaks[0]["items"], 12);
    let frames = leaks[0]["frames"].as_u64().expect("frames");
    assert_eq!(
        frames as usize, mirrored.frames,
        "every frame of the release"
    );
    // An import reports it as it finishes, and audits it.
    let again = import(&server.pool, &root, &options("again")).await;
    assert_eq!(again.leaks.len(), 1, "{:?}", again.leaks);
    assert_eq!(
        (again.leaks[0].dataset.as_str(), again.leaks[0].items),
        ("mirror", 12)
    );
    assert!(again.summary_line().contains("public dataset 'mirror'"));
    let audited = enact_hub::app::audit::list(
        &hub,
        enact_hub::core::audit::AuditFilter {
            action: Some("dataset.leak".to_owned()),
            limit: 10,
            ..Default::default()
        },
    )
    .await
    .expect("the audit log");
    assert_eq!(audited.len(), 1, "{audited:?}");
    assert_eq!(audited[0].target, "dataset again");
    assert!(
        audited[0].detail.contains("12 items"),
        "{}",
        audited[0].detail
    );
    // A public dataset's own flags skip what public answers make moot.
    let public = server
        .call(Method::GET, "/api/v1/admin/datasets/mirror/flags")
        .bearer(&admin)
        .expect(200)
        .await
        .json();
    assert_eq!(public["answers"], "public");
    assert!(public["leaks"].as_array().expect("leaks").is_empty());
    assert!(
        public["identical_to_truth"]
            .as_array()
            .expect("list")
            .is_empty()
    );
}
