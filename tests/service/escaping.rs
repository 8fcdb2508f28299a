//! Markup typed by users (a model name, a description, an account name, a flag reason) is shown
//! as text on every page (the audit log's included), in every SVG and in every report file. Annotator names cannot carry
//! markup at all.

use enact_hub::core::credentials::Role;
use reqwest::StatusCode;
use serde_json::Value;

use crate::annotate::{annotator, assign, logged_in_on, report_bundle};
use crate::helpers::*;

const MODEL: &str = "<script>alert('m')</script>&x";
const ACCOUNT: &str = "<b>bold</b> team";
const DESCRIPTION: &str = "<img src=x onerror=alert(1)>";
const REASON: &str = "<iframe src=javascript:alert(2)></iframe>";

/// No raw tag of ours in `text`, and at least one escaped form of it when `shown`.
fn escaped(what: &str, text: &str, shown: bool) {
    for raw in ["<script>", "<img src=x", "<iframe", "<b>bold"] {
        assert!(!text.contains(raw), "{what} shows {raw:?} unescaped");
    }
    if shown {
        assert!(
            text.contains("&lt;script&gt;") || text.contains("&#60;script&#62;"),
            "{what} does not show the model name at all"
        );
    }
}

#[tokio::test]
async fn markup_from_users_is_text_everywhere() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, ACCOUNT, Role::Submitter, None, None).await;
    let query = serde_urlencoded::to_string([("model", MODEL), ("description", DESCRIPTION)])
        .expect("query");
    let reply = submit_to(&server, "mini", &query, &token, answers(&records, &[0])).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let id = reply.id();
    assert_eq!(reply.json()["model"], MODEL, "stored as given");

    // A flag whose reason is markup, and a human answer so the report has a Human row.
    let ann = annotator(&server, "ann", false).await;
    annotator(&server, "root", true).await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    let other = records[1]["id"].as_str().expect("id").to_owned();
    assign(&server, ann, &[&item, &other]).await;
    let (mut alice, csrf) = logged_in_on(&server, "ann", "/annotate").await;
    let r = alice
        .post_form(
            &format!("/annotate/mini/{item}/skip"),
            &[("csrf", &csrf), ("reason", REASON), ("action", "flag")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);

    // Annotator names cannot carry markup: the CLI refuses one.
    let out = enact_hub()
        .args(["annotator", "create", "--name", "<b>eve</b>", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    assert!(!out.status.success());

    // Every public page that shows the submission.
    for path in [
        "/",
        "/datasets/mini",
        "/leaderboard/mini",
        "/leaderboard/mini?all=1",
        "/leaderboard/mini/errors",
        &format!("/leaderboard/mini/errors/{id}"),
    ] {
        let html = server.get(path).await.text().await.expect("body");
        let shows = !matches!(path, "/" | "/datasets/mini");
        escaped(path, &html, shows);
    }
    // The admin's pages and the report bundle: every file.
    let (mut root, _) = logged_in_on(&server, "root", "/admin").await;
    let (status, html) = root.text("/admin").await;
    assert_eq!(status, StatusCode::OK);
    escaped("/admin", &html, false);
    assert!(
        html.contains("&#60;iframe") || html.contains("&lt;iframe"),
        "the flag reason is shown, escaped: {html}"
    );
    // The audit log holds the model name (submission) and the flag reason (annotation).
    let (status, html) = root.text("/admin/audit").await;
    assert_eq!(status, StatusCode::OK);
    escaped("/admin/audit", &html, true);
    assert!(html.contains("&#60;iframe") || html.contains("&lt;iframe"));
    let (status, html) = root.text("/admin/datasets/mini/report?bootstrap=0").await;
    assert_eq!(status, StatusCode::OK);
    escaped("/admin/datasets/mini/report", &html, true);
    let mut files = 0;
    for (path, text) in report_bundle(&mut root, "mini", "?bootstrap=0").await {
        if path.ends_with(".svg") || path.ends_with(".md") {
            // Drawn or rendered as markup: escaped.
            escaped(&path, &text, path.ends_with(".md"));
        } else if path.ends_with(".tex") {
            assert!(
                !text.contains("<script>"),
                "{path}: markup survives into LaTeX"
            );
            assert!(text.contains("\\&"), "{path}: & is escaped for LaTeX");
        } else if path.ends_with(".json") {
            // JSON carries the name as data; a reader must parse it, not paste it.
            let _: Value = serde_json::from_str(&text).expect("valid JSON");
        }
        files += 1;
    }
    assert_eq!(files, 12);
    server.stop().await;
}
