//! Reported results and model metadata (issue 37): the ENACT paper's results imported from the
//! command line beside a running server and shown on the leaderboard only with the switch;
//! another paper's JSON tables refused whole on a bad field; rows added and removed by admins
//! through the API, audited; a model's metadata set by its submitter or an admin and carried
//! in the leaderboard's rows.

use enact_hub::app::Hub;
use enact_hub::core::audit::AuditFilter;
use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

/// `enact-hub ARGS`: whether it succeeded, its stdout and its stderr.
fn run(args: &[&str]) -> (bool, String, String) {
    let out = enact_hub().args(args).output().expect("enact-hub runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
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

async fn page(server: &TestServer, path: &str, accept_language: &str) -> String {
    let r = reqwest::Client::new()
        .get(server.url(path))
        .header("accept-language", accept_language)
        .send()
        .await
        .expect("get");
    assert_eq!(r.status(), 200, "{path}");
    r.text().await.expect("body")
}

/// The audit entries of `action`, newest first.
async fn audit_of(server: &TestServer, action: &str) -> Vec<enact_hub::core::audit::AuditEntry> {
    enact_hub::app::audit::list(
        &Hub::from(server.pool.clone()),
        AuditFilter {
            action: Some(action.to_owned()),
            limit: 10,
            ..AuditFilter::default()
        },
    )
    .await
    .expect("audit")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_paper_s_results_import_beside_a_running_server_and_show_only_with_the_switch() {
    let (server, _) = spawn_app_with_release().await;
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    // The board is built and cached before the import: the server sees the rows only because
    // the command line announces them.
    let before = board(&server, "reported=1").await;
    assert_eq!(before["reported"], json!([]), "{before}");

    let (ok, out, err) = run(&[
        "reported",
        "import",
        "--paper",
        "--db",
        db,
        "--dataset",
        "mini",
    ]);
    assert!(ok, "{out}{err}");
    assert!(
        out.contains("31 reported rows stored (0 replacing"),
        "{out}"
    );

    let since = std::time::Instant::now();
    let shown = loop {
        let shown = board(&server, "reported=1").await;
        if shown["reported"].as_array().is_some_and(|r| r.len() == 31) {
            break shown;
        }
        assert!(
            since.elapsed() < std::time::Duration::from_secs(2),
            "the running server still shows {shown} after 2 s"
        );
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    };
    let gpt5 = &shown["reported"][0];
    assert_eq!(gpt5["model"], "GPT-5", "{gpt5}");
    assert_eq!(gpt5["category"], "proprietary");
    assert_eq!(gpt5["task_accuracy"]["forward_3"], 80.59);
    assert_eq!(gpt5["pairwise_accuracy"]["forward_3"], 84.62);
    assert!(
        gpt5["source"]
            .as_str()
            .is_some_and(|s| s.contains("tab:app_task_acc")),
        "{gpt5}"
    );
    let human = &shown["reported"][30];
    assert_eq!(human["category"], "human", "{human}");
    // Never ranked, never among the scored rows.
    assert!(
        shown["rows"].as_array().expect("rows").is_empty(),
        "{shown}"
    );

    // Hidden by default, in the API and on the page.
    let hidden = board(&server, "").await;
    assert!(hidden.get("reported").is_none(), "{hidden}");
    let listed = server
        .call(Method::GET, "/api/v1/datasets/mini/reported")
        .expect(200)
        .await
        .json();
    assert_eq!(listed["reported"].as_array().map(Vec::len), Some(31));

    let en = page(&server, "/leaderboard/mini", "en").await;
    assert!(!en.contains("GPT-5"), "reported rows are hidden by default");
    assert!(en.contains("Show reported rows"), "{en}");
    assert!(
        en.contains("/leaderboard/mini?sort=overall_ta&#38;page=1&#38;per_page=50&#38;reported=1"),
        "{en}"
    );
    let en = page(&server, "/leaderboard/mini?reported=1", "en").await;
    assert!(en.contains("GPT-5"), "{en}");
    assert!(en.contains(r#"<span class="tag">reported</span>"#), "{en}");
    assert!(en.contains("Hide reported rows"), "{en}");
    assert!(en.contains("never ranked against the hub"), "{en}");
    // GPT-5's forward TA at L=3 as the page prints percentages.
    assert!(en.contains(">80.6<"), "{en}");
    let zh = page(&server, "/leaderboard/mini?reported=1", "zh-CN").await;
    assert!(zh.contains("GPT-5"), "{zh}");
    assert!(zh.contains("隐藏报告行"), "{zh}");
    assert!(zh.contains(r#"<span class="tag">报告</span>"#), "{zh}");

    // Importing again replaces the same rows rather than doubling them.
    let (ok, out, err) = run(&[
        "reported",
        "import",
        "--paper",
        "--db",
        db,
        "--dataset",
        "mini",
    ]);
    assert!(ok, "{out}{err}");
    assert!(
        out.contains("31 reported rows stored (31 replacing"),
        "{out}"
    );
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM reported_results").await,
        31
    );
    let entries = audit_of(&server, "reported.add").await;
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].dataset.as_deref(), Some("mini"));
    server.stop().await;
}

/// A table of `metric` in the JSON shape `paper` writes, with `rows` of (model, forward_3).
fn table(metric: &str, rows: &[(&str, Value)]) -> String {
    json!({
        "metric": metric,
        "rows": rows.iter().map(|(model, value)| json!({
            "model": model,
            "category": "open-weight",
            "source": "Another paper, Table 2",
            "cells": {"forward_3": {"value": value, "mark": null}, "inverse_10": {"value": 12.5, "mark": "first"}},
        })).collect::<Vec<_>>(),
    })
    .to_string()
}

#[tokio::test]
async fn another_paper_s_tables_are_merged_by_model_and_a_bad_field_stores_nothing() {
    let (server, _) = spawn_app_with_release().await;
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let dir = server.dir();
    let ta = dir.join("ta.json");
    let pa = dir.join("pa.json");
    let bad = dir.join("pa-bad.json");
    std::fs::write(
        &ta,
        table(
            "task_accuracy",
            &[("Model-A", json!(41.0)), ("Model-B", json!(7.25))],
        ),
    )
    .expect("write");
    std::fs::write(
        &pa,
        table(
            "pairwise_accuracy",
            &[("Model-A", json!(60.5)), ("Model-B", json!(55.0))],
        ),
    )
    .expect("write");
    std::fs::write(
        &bad,
        table(
            "pairwise_accuracy",
            &[("Model-A", json!(60.5)), ("Model-B", json!(120))],
        ),
    )
    .expect("write");
    let path = |p: &std::path::Path| p.to_str().expect("utf-8 path").to_owned();

    let (ok, out, err) = run(&[
        "reported",
        "import",
        &path(&ta),
        &path(&bad),
        "--db",
        db,
        "--dataset",
        "mini",
    ]);
    assert!(!ok, "{out}");
    assert!(
        err.contains(
            "pa-bad.json: row 2 (Model-B): cells.forward_3.value: 120 is not a percentage"
        ),
        "{err}"
    );
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM reported_results").await,
        0,
        "nothing of a refused import is stored"
    );
    assert!(audit_of(&server, "reported").await.is_empty());

    let (ok, out, err) = run(&[
        "reported",
        "import",
        &path(&ta),
        &path(&pa),
        "--db",
        db,
        "--dataset",
        "mini",
    ]);
    assert!(ok, "{out}{err}");
    assert!(out.contains("2 reported rows stored"), "{out}");
    let listed = server
        .call(Method::GET, "/api/v1/datasets/mini/reported")
        .expect(200)
        .await
        .json();
    let rows = listed["reported"].as_array().expect("rows");
    assert_eq!(rows.len(), 2, "{listed}");
    assert_eq!(rows[1]["model"], "Model-B");
    assert_eq!(rows[1]["task_accuracy"]["forward_3"], 7.25);
    assert_eq!(rows[1]["pairwise_accuracy"]["forward_3"], 55.0);
    assert_eq!(rows[1]["pairwise_accuracy"]["inverse_10"], 12.5);

    let (ok, out, _) = run(&["reported", "list", "--db", db, "--dataset", "mini"]);
    assert!(ok && out.contains("Model-A\topen-weight"), "{out}");

    // A model twice in tables of one metric is refused, naming both places.
    let (ok, _, err) = run(&[
        "reported",
        "import",
        &path(&ta),
        &path(&ta),
        "--db",
        db,
        "--dataset",
        "mini",
    ]);
    assert!(!ok);
    assert!(
        err.contains("ta.json: row 1 (Model-A): model: also in row 1 of"),
        "{err}"
    );
    server.stop().await;
}

#[tokio::test]
async fn admins_add_and_remove_reported_rows_through_the_api_audited() {
    let (server, _) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "boss", Role::Admin, None, None).await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let row = json!({
        "model": "GPT-5",
        "category": "proprietary",
        "source": "ENACT paper, Table 1",
        "task_accuracy": {"forward_3": 80.59},
        "pairwise_accuracy": {"forward_3": 84.62, "inverse_10": 70.1},
    });
    let path = "/api/v1/datasets/mini/reported";
    server.call(Method::POST, path).json(&row).expect(401).await;
    server
        .call(Method::POST, path)
        .bearer(&team)
        .json(&row)
        .expect(403)
        .await;
    let added = server
        .call(Method::POST, path)
        .bearer(&admin)
        .json(&row)
        .expect(201)
        .await;
    let id = added.id();
    assert_eq!(added.json()["added_by"], "account boss");
    let twice = server
        .call(Method::POST, path)
        .bearer(&admin)
        .json(&row)
        .expect(409)
        .await;
    assert!(
        twice.error().contains("already has a reported row"),
        "{}",
        twice.text
    );
    let mut bad = row.clone();
    bad["source"] = json!("elsewhere");
    bad["task_accuracy"]["inverse_4"] = json!(101.0);
    let refused = server
        .call(Method::POST, path)
        .bearer(&admin)
        .json(&bad)
        .expect(400)
        .await;
    assert!(
        refused
            .error()
            .contains("task_accuracy.inverse_4: 101 is not a percentage"),
        "{}",
        refused.text
    );

    let shown = board(&server, "reported=1").await;
    assert_eq!(shown["reported"][0]["id"], id, "{shown}");
    let one = format!("{path}/{id}");
    server
        .call(Method::DELETE, &one)
        .bearer(&team)
        .expect(403)
        .await;
    server
        .call(Method::DELETE, &one)
        .bearer(&admin)
        .expect(204)
        .await;
    server
        .call(Method::DELETE, &one)
        .bearer(&admin)
        .expect(404)
        .await;
    let shown = board(&server, "reported=1").await;
    assert_eq!(shown["reported"], json!([]), "{shown}");

    let added = audit_of(&server, "reported.add").await;
    let removed = audit_of(&server, "reported.remove").await;
    assert_eq!((added.len(), removed.len()), (1, 1));
    assert_eq!(added[0].actor, "boss");
    assert_eq!(removed[0].target, format!("reported result {id} (GPT-5)"));
    server.stop().await;
}

#[tokio::test]
async fn a_model_s_metadata_is_set_by_its_submitter_or_an_admin_and_carried_in_the_rows() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "boss", Role::Admin, None, None).await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let (_, bob) = api_token(&server.pool, "bob", Role::Submitter, None, None).await;
    for (token, model) in [(&alice, "model-a"), (&bob, "model-b")] {
        let reply = submit_to(
            &server,
            "mini",
            &format!("model={model}"),
            token,
            answers(&records, &[0]),
        )
        .await;
        assert_eq!(reply.status, 201, "{}", reply.text);
    }
    let path = |model: &str| format!("/api/v1/datasets/mini/models/{model}");
    let metadata = json!({
        "category": "open-weight",
        "family": "Qwen2.5-VL",
        "size": "7B",
        "link": "https://huggingface.co/Qwen/Qwen2.5-VL-7B-Instruct",
    });
    let set = server
        .call(Method::PUT, &path("model-a"))
        .bearer(&alice)
        .json(&metadata)
        .expect(200)
        .await
        .json();
    assert_eq!(set["family"], "Qwen2.5-VL", "{set}");
    assert_eq!(set["updated_by"], "account alice");
    // Another account's model.
    let refused = server
        .call(Method::PUT, &path("model-b"))
        .bearer(&alice)
        .json(&metadata)
        .expect(403)
        .await;
    assert!(
        refused.error().contains("submitted by another account"),
        "{}",
        refused.text
    );
    // A submitter keeps to the paper's categories; links are http(s) URLs.
    let refused = server
        .call(Method::PUT, &path("model-a"))
        .bearer(&alice)
        .json(&json!({"category": "frontier"}))
        .expect(400)
        .await;
    assert!(
        refused.error().starts_with("`category`"),
        "{}",
        refused.text
    );
    let refused = server
        .call(Method::PUT, &path("model-a"))
        .bearer(&alice)
        .json(&json!({"link": "javascript:alert(1)"}))
        .expect(400)
        .await;
    assert!(refused.error().starts_with("`link`"), "{}", refused.text);
    server
        .call(Method::PUT, &path("no-such-model"))
        .bearer(&admin)
        .json(&metadata)
        .expect(404)
        .await;
    // An admin sets anyone's, and may name a category.
    server
        .call(Method::PUT, &path("model-b"))
        .bearer(&admin)
        .json(&json!({"category": "hub baselines", "size": "72B"}))
        .expect(200)
        .await;

    let shown = board(&server, "").await;
    let row = |model: &str| {
        shown["rows"]
            .as_array()
            .expect("rows")
            .iter()
            .find(|r| r["model"] == model)
            .cloned()
            .unwrap_or_else(|| panic!("no row of {model}: {shown}"))
    };
    assert_eq!(row("model-a")["metadata"], metadata);
    assert_eq!(
        row("model-b")["metadata"],
        json!({"category": "hub baselines", "family": null, "size": "72B", "link": null})
    );
    let html = page(&server, "/leaderboard/mini", "en").await;
    assert!(html.contains("open-weight · Qwen2.5-VL · 7B"), "{html}");
    assert!(
        html.contains(r#"<a href="https://huggingface.co/Qwen/Qwen2.5-VL-7B-Instruct" rel="nofollow noopener">about the model</a>"#),
        "{html}"
    );

    let entries = audit_of(&server, "model.metadata").await;
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].actor, "boss");
    assert_eq!(entries[1].actor, "alice");
    assert_eq!(entries[1].target, "model model-a");
    server.stop().await;
}

/// The admin page of a dataset's reported results and model metadata: lists the rows, imports
/// the paper's results or a pasted table, removes a row, sets a model's metadata, every change
/// audited; a refused table names its row and field and stores nothing; anyone but an admin
/// with the page's CSRF token is refused.
#[tokio::test]
async fn the_admin_page_imports_removes_and_sets_metadata_audited() {
    use crate::annotate::{Browser, annotator, logged_in_on};

    let (server, records) = spawn_app_with_release().await;
    annotator(&server, "root", true).await;
    annotator(&server, "ann", false).await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let reply = submit_to(
        &server,
        "mini",
        "model=model-a",
        &team,
        answers(&records, &[0]),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let stored = || count(&server.pool, "SELECT count(*) FROM reported_results");
    let path = "/admin/datasets/mini/reported";
    let (mut admin, csrf) = logged_in_on(&server, "root", "/admin").await;

    let (status, home) = admin.text("/admin").await;
    assert_eq!(status, 200);
    assert!(
        home.contains(r#"<a href="/admin/datasets/mini/reported">"#),
        "{home}"
    );
    let (status, empty) = admin.text(path).await;
    assert_eq!(status, 200, "{empty}");
    assert!(empty.contains("No reported result yet."), "{empty}");
    assert!(empty.contains("<option>model-a</option>"), "{empty}");

    // The ENACT paper's results, from the page's button.
    let r = admin
        .post_form(&format!("{path}/paper"), &[("csrf", &csrf)])
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(
        html.contains("Stored 31 reported rows on &#39;mini&#39; (0 replacing"),
        "{html}"
    );
    assert!(
        html.contains("<td>GPT-5</td><td>proprietary</td>"),
        "{html}"
    );
    assert_eq!(stored().await, 31);
    let added = audit_of(&server, "reported.add").await;
    assert_eq!(added.len(), 1);
    assert_eq!(added[0].actor, "root");
    assert_eq!(added[0].target, "reported results from the ENACT paper");

    // One row removed by its button.
    let listed = server
        .call(Method::GET, "/api/v1/datasets/mini/reported")
        .expect(200)
        .await
        .json();
    let first = &listed["reported"][0];
    assert_eq!(first["model"], "GPT-5", "{listed}");
    let id = first["id"].as_i64().expect("id").to_string();
    let r = admin
        .post_form(&format!("{path}/remove"), &[("csrf", &csrf), ("id", &id)])
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(
        html.contains(&format!("Removed reported result {id}.")),
        "{html}"
    );
    assert!(
        !html.contains("<td>GPT-5</td><td>proprietary</td>"),
        "{html}"
    );
    assert_eq!(stored().await, 30);
    let removed = audit_of(&server, "reported.remove").await;
    assert_eq!(removed.len(), 1);
    assert_eq!(removed[0].target, format!("reported result {id} (GPT-5)"));

    // A pasted table with a bad value: refused whole, naming row and field, kept in the form.
    let bad = table(
        "pairwise_accuracy",
        &[("Model-A", json!(60.5)), ("Model-B", json!(120))],
    );
    let r = admin
        .post_form(
            &format!("{path}/tables"),
            &[("csrf", &csrf), ("table", &bad)],
        )
        .await;
    assert_eq!(r.status(), 400);
    let html = r.text().await.expect("body");
    assert!(
        html.contains(
            "Nothing was stored: pasted.json: row 2 (Model-B): cells.forward_3.value: 120 is \
             not a percentage"
        ),
        "{html}"
    );
    assert!(
        html.contains("Another paper, Table 2"),
        "the table stays in its field"
    );
    assert_eq!(stored().await, 30);
    assert_eq!(audit_of(&server, "reported.add").await.len(), 1);

    // A good one.
    let good = table("task_accuracy", &[("Model-A", json!(41.0))]);
    let r = admin
        .post_form(
            &format!("{path}/tables"),
            &[("csrf", &csrf), ("table", &good)],
        )
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(html.contains("Stored 1 reported rows"), "{html}");
    assert!(html.contains("<td>Model-A</td>"), "{html}");
    assert_eq!(stored().await, 31);
    let added = audit_of(&server, "reported.add").await;
    assert_eq!(added[0].target, "reported results from pasted.json");

    // A submitted model's metadata, any category for an admin; a bad link refused.
    let metadata = |link: &'static str| {
        [
            ("csrf", csrf.clone()),
            ("model", "model-a".to_owned()),
            ("category", "hub baselines".to_owned()),
            ("family", "Qwen2.5-VL".to_owned()),
            ("size", "7B".to_owned()),
            ("link", link.to_owned()),
        ]
    };
    let fields = metadata("javascript:alert(1)");
    let fields: Vec<(&str, &str)> = fields.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let r = admin
        .post_form("/admin/datasets/mini/models", &fields)
        .await;
    assert_eq!(r.status(), 400);
    let html = r.text().await.expect("body");
    assert!(html.contains("Nothing was stored: `link`"), "{html}");
    assert!(audit_of(&server, "model.metadata").await.is_empty());
    let fields = metadata("https://example.org/model-a");
    let fields: Vec<(&str, &str)> = fields.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let r = admin
        .post_form("/admin/datasets/mini/models", &fields)
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(
        html.contains("Set the metadata of model &#39;model-a&#39;."),
        "{html}"
    );
    assert!(
        html.contains("<tr><td>model-a</td><td>hub baselines</td><td>Qwen2.5-VL</td><td>7B</td>"),
        "{html}"
    );
    let shown = board(&server, "").await;
    assert_eq!(
        shown["rows"][0]["metadata"],
        json!({"category": "hub baselines", "family": "Qwen2.5-VL", "size": "7B",
               "link": "https://example.org/model-a"}),
        "{shown}"
    );
    let set = audit_of(&server, "model.metadata").await;
    assert_eq!(set.len(), 1);
    assert_eq!(
        (set[0].actor.as_str(), set[0].target.as_str()),
        ("root", "model model-a")
    );

    // Refused: a wrong CSRF token, an annotator, anyone without a session.
    let wrong = "0".repeat(64);
    let r = admin
        .post_form(&format!("{path}/paper"), &[("csrf", &wrong)])
        .await;
    assert_eq!(r.status(), 403);
    let r = admin
        .post_form(&format!("{path}/remove"), &[("id", &id)])
        .await;
    assert_eq!(r.status(), 403);
    let (mut ann, ann_csrf) = logged_in_on(&server, "ann", "/annotate").await;
    assert_eq!(ann.get(path).await.status(), 403);
    let r = ann
        .post_form(&format!("{path}/paper"), &[("csrf", &ann_csrf)])
        .await;
    assert_eq!(r.status(), 403);
    let mut anonymous = Browser::new(&server);
    let r = anonymous.get(path).await;
    assert_eq!(r.status(), 303);
    assert!(
        r.headers()
            .get("location")
            .and_then(|l| l.to_str().ok())
            .is_some_and(|l| l.starts_with("/login")),
        "{r:?}"
    );
    let r = anonymous
        .post_form(&format!("{path}/paper"), &[("csrf", &csrf)])
        .await;
    assert_eq!(r.status(), 401);
    assert_eq!(stored().await, 31, "nothing refused was stored");
    assert_eq!(audit_of(&server, "reported.add").await.len(), 2);
    server.stop().await;
}
