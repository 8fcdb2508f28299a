//! The model-run pages: start a run from the admin form (its key chosen by variable name), see
//! and control its progress, read its per-item responses a page at a time and download them as
//! ENACT's model-output JSONL; the public side shows them only for datasets with public answers.

use std::time::Duration;

use enact_hub::app::Hub;
use enact_hub::app::jobs::Worker;
use enact_hub::app::runs;
use enact_hub::core::credentials::Role;
use enact_hub::core::dataset::AnswerVisibility;
use reqwest::{Method, StatusCode};
use serde_json::Value;

use crate::annotate::{Browser, PASSWORD, annotator, hidden_csrf};
use crate::helpers::*;
use crate::runs::{SECRET_KEY, answer_text, run_fixture, scripts};
use crate::server_runs::{KEY_VARIABLE, fast, keyed};
use crate::standin::{StandIn, StandInConfig, Step};

fn form<'a>(csrf: &'a str, standin: &'a str, temperature: &'a str) -> Vec<(&'a str, &'a str)> {
    vec![
        ("csrf", csrf),
        ("dataset", "mini"),
        ("endpoint", standin),
        ("model", "standin-vl"),
        ("key_variable", KEY_VARIABLE),
        ("name", "from-the-page"),
        ("submit_as", ""),
        ("temperature", temperature),
        ("max_tokens", "256"),
        ("limit", ""),
        ("price_input", "2.5"),
        ("price_output", "10"),
        ("concurrency", "2"),
        ("max_retries", "0"),
        ("timeout_s", "5"),
    ]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_admin_starts_a_run_from_the_page_controls_it_and_reads_its_responses() {
    let (dir, pool, records) = run_fixture(1).await;
    let root = dir.path().join("release");
    // Item 0 is refused by the endpoint (a 400 fails at once), item 1 is cut off.
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |i, r| match i {
            0 => vec![Step::Status(
                400,
                "image too large for this model".to_owned(),
            )],
            1 => vec![Step::Cut("The order is [".to_owned())],
            _ => vec![Step::Answer(answer_text(r, true))],
        }),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    annotator(&server, "boss", true).await;
    annotator(&server, "ann", false).await;
    let mut pages = Vec::new();

    // Only admins see the runs pages.
    let mut stranger = Browser::new(&server);
    let (status, _) = stranger.text("/admin/runs").await;
    assert_ne!(status, StatusCode::OK);
    let mut annotator_browser = Browser::new(&server);
    annotator_browser.login("ann", PASSWORD).await;
    let (status, _) = annotator_browser.text("/admin/runs").await;
    assert_eq!(status, StatusCode::FORBIDDEN);

    let mut browser = Browser::new(&server);
    assert_eq!(
        browser.login("boss", PASSWORD).await.status(),
        StatusCode::SEE_OTHER
    );
    let (status, list) = browser.text("/admin/runs").await;
    assert_eq!(status, StatusCode::OK);
    assert!(list.contains("No run yet"), "{list}");
    // The key is offered by its variable's name, never by its value.
    assert!(
        list.contains(&format!("<option value=\"{KEY_VARIABLE}\">")),
        "{list}"
    );
    assert!(!list.contains(SECRET_KEY));
    let csrf = hidden_csrf(&list);
    let endpoint = standin.endpoint();

    // A bad field is named; nothing is started.
    let r = browser
        .post_form("/admin/runs", &form(&csrf, &endpoint, "warm"))
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let text = r.text().await.expect("body");
    assert!(
        text.contains("temperature") && text.contains("warm"),
        "{text}"
    );
    let mut refused = form(&csrf, &endpoint, "0");
    refused[4] = ("key_variable", "HOME");
    let r = browser.post_form("/admin/runs", &refused).await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(r.text().await.expect("body").contains("HOME"));
    assert!(runs::list(&hub).await.expect("runs").is_empty());

    let r = browser
        .post_form("/admin/runs", &form(&csrf, &endpoint, "0"))
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    let location = r.headers()["location"].to_str().expect("ascii").to_owned();
    let run = runs::by_name(&hub, "from-the-page").await.expect("the run");
    assert_eq!(location, format!("/admin/runs/{}", run.id));
    assert!(run.job.is_some(), "the run is linked to its job");

    // Queued: it can be paused or cancelled, not resumed (the other button is hidden).
    let (status, page) = browser.text(&location).await;
    assert_eq!(status, StatusCode::OK);
    assert!(page.contains("queued"), "{page}");
    assert!(page.contains("data-when=\"queued running\">"), "{page}");
    assert!(
        page.contains("data-when=\"paused failed\" hidden>"),
        "{page}"
    );
    let control = format!("{location}/control");
    let r = browser
        .post_form(&control, &[("csrf", &csrf), ("change", "pause")])
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let page = r.text().await.expect("body");
    assert!(page.contains("Paused") && page.contains("paused"), "{page}");
    assert!(page.contains("data-when=\"paused failed\">"), "{page}");
    let r = browser
        .post_form(&control, &[("csrf", &csrf), ("change", "explode")])
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let r = browser
        .post_form(&control, &[("csrf", &csrf), ("change", "resume")])
        .await;
    assert_eq!(r.status(), StatusCode::OK);

    let worker = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    let mut shown = Value::Null;
    for _ in 0..1500 {
        let (status, progress) = browser.text(&format!("{location}/progress")).await;
        assert_eq!(status, StatusCode::OK);
        shown = serde_json::from_str(&progress).expect("JSON progress");
        if shown["state"] == "done" {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    worker.stop().await;
    assert_eq!(shown["state"], "done", "{shown}");
    assert_eq!(shown["progress"]["failed"], 2, "{shown}");

    // The run's page: its figures, the failures with their reasons, every reply.
    let (status, page) = browser.text(&location).await;
    assert_eq!(status, StatusCode::OK);
    assert!(page.contains("done (submitted)"), "{page}");
    let n = records.len();
    assert!(page.contains(&format!("{n} of {n}")), "{page}");
    assert!(page.contains("image too large for this model"), "{page}");
    assert!(page.contains("<td>length</td>"), "{page}");
    for r in &records {
        assert!(page.contains(r["id"].as_str().expect("id")), "{page}");
    }
    assert!(page.contains("Page 1 of 1"), "{page}");
    let (status, _) = browser.text(&format!("{location}?page=0")).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    let (status, past) = browser.text(&format!("{location}?page=2")).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(past.contains("1 page(s)"), "{past}");
    pages.push(page);

    // The answers as model-output JSONL: answered items only, from the page and the API.
    let (status, jsonl) = browser.text(&format!("{location}/responses.jsonl")).await;
    assert_eq!(status, StatusCode::OK);
    let lines: Vec<Value> = jsonl
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(lines.len(), n - 2);
    for (line, record) in lines.iter().zip(&records[2..]) {
        assert_eq!(line["id"], record["id"]);
        assert_eq!(line["gt_answer"], record["gt_answer"]);
        assert_eq!(line["answer"], answer_text(record, true));
    }
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let api = server
        .call(
            Method::GET,
            &format!("/api/v1/admin/runs/{}/responses", run.id),
        )
        .bearer(&admin)
        .expect(200)
        .await;
    assert_eq!(api.text, jsonl);
    assert_eq!(
        api.headers["content-disposition"],
        "attachment; filename=\"enact_ordering_standin-vl.jsonl\""
    );

    // The public side: nothing while the dataset's answers are hidden, the same once public.
    let public = format!("/runs/{}", run.id);
    let (status, _) = stranger.text(&public).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    server
        .call(Method::GET, &format!("/api/v1/runs/{}/responses", run.id))
        .expect(404)
        .await;
    let link = format!("href=\"/runs/{}\"", run.id);
    let (_, dataset_page) = stranger.text("/datasets/mini").await;
    assert!(!dataset_page.contains(&link), "{dataset_page}");
    set_mini_answers(&pool, AnswerVisibility::Public).await;
    let (_, dataset_page) = stranger.text("/datasets/mini").await;
    assert!(
        dataset_page.contains(&link),
        "the dataset page links the run"
    );
    let (status, page) = stranger.text(&public).await;
    assert_eq!(status, StatusCode::OK);
    assert!(page.contains("image too large for this model"), "{page}");
    let (status, file) = stranger.text(&format!("{public}/responses.jsonl")).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(file, jsonl);
    let api = server
        .call(Method::GET, &format!("/api/v1/runs/{}/responses", run.id))
        .expect(200)
        .await;
    assert_eq!(api.text, jsonl);
    pages.push(page);

    let (_, list) = browser.text("/admin/runs").await;
    assert!(
        list.contains("from-the-page") && list.contains("done"),
        "{list}"
    );
    pages.push(list);
    assert!(pages.iter().all(|p| !p.contains(SECRET_KEY)));
    server.stop().await;
}
