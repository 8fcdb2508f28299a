//! The audit log: every audited use case writes one entry with its actor, target and dataset,
//! in the same transaction; refused actions write none; the admin page, `enact-hub audit` and
//! the report bundle show the same entries.

use std::collections::BTreeSet;

use enact_hub::core::credentials::Role;
use reqwest::{Method, StatusCode};
use serde_json::{Value, json};

use crate::annotate::{annotator, logged_in_on, report_bundle};
use crate::helpers::*;

/// `enact-hub audit --json` with extra arguments, as parsed JSON.
fn audit_cli(server: &TestServer, args: &[&str]) -> Vec<Value> {
    let out = enact_hub()
        .arg("audit")
        .arg("--db")
        .arg(server.db_path())
        .arg("--json")
        .args(args)
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice::<Vec<Value>>(&out.stdout).expect("a JSON array")
}

fn actions(entries: &[Value]) -> BTreeSet<String> {
    entries
        .iter()
        .map(|e| e["action"].as_str().expect("action").to_owned())
        .collect()
}

/// The one entry with this action (and, when given, this target).
fn entry<'a>(entries: &'a [Value], action: &str, target: Option<&str>) -> &'a Value {
    let found: Vec<&Value> = entries
        .iter()
        .filter(|e| e["action"] == action && target.is_none_or(|t| e["target"] == t))
        .collect();
    assert_eq!(found.len(), 1, "{action} {target:?} in {entries:#?}");
    found[0]
}

#[tokio::test]
async fn every_audited_action_names_its_actor_target_and_dataset() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin_token) = api_token(&server.pool, "boss", Role::Admin, None, None).await;

    // Over the API, as the account "boss".
    let created = server
        .call(Method::POST, "/api/v1/admin/tokens")
        .bearer(&admin_token)
        .json(&json!({"name": "team", "daily_quota": 3}))
        .expect(201)
        .await
        .json();
    let team_token = created["token"].as_str().expect("token").to_owned();
    let prefix = created["prefix"].as_str().expect("prefix").to_owned();
    let reply = submit_to(
        &server,
        "mini",
        "model=m1",
        &team_token,
        answers(&records, &[0]),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let submission = reply.id();
    server
        .call(
            Method::PATCH,
            &format!("/api/v1/admin/submissions/{submission}"),
        )
        .bearer(&admin_token)
        .json(&json!({"visibility": "hidden", "baseline": true}))
        .expect(200)
        .await;
    server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/answers")
        .bearer(&admin_token)
        .json(&json!({"answers": "public"}))
        .expect(200)
        .await;
    server
        .call(Method::DELETE, &format!("/api/v1/admin/tokens/{prefix}"))
        .bearer(&admin_token)
        .expect(204)
        .await;

    // Refused actions leave no entry.
    let before = audit_cli(&server, &[]).len();
    server
        .call(Method::DELETE, "/api/v1/admin/tokens/ehub_nosuch")
        .bearer(&admin_token)
        .expect(404)
        .await;
    submit_to(
        &server,
        "mini",
        "model=m2",
        &team_token,
        answers(&records, &[]),
    )
    .await;
    server
        .call(Method::PATCH, "/api/v1/admin/submissions/999999")
        .bearer(&admin_token)
        .json(&json!({"visibility": "hidden"}))
        .expect(404)
        .await;
    assert_eq!(
        audit_cli(&server, &[]).len(),
        before,
        "a refusal was logged"
    );

    // On the admin pages, as the annotator "root"; then an annotator's answer and skip.
    annotator(&server, "root", true).await;
    let alice = annotator(&server, "alice", false).await;
    let (mut root, csrf) = logged_in_on(&server, "root", "/admin").await;
    let r = root
        .post_form("/admin/annotators", &[("csrf", &csrf), ("name", "bob")])
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let items: Vec<String> = records[..2]
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    let r = root
        .post_form(
            "/admin/assign",
            &[
                ("csrf", &csrf),
                ("dataset", "mini"),
                ("mode", "list"),
                ("annotator", &alice.to_string()),
                ("items", &items.join("\n")),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let (mut browser, csrf_alice) = logged_in_on(&server, "alice", "/annotate").await;
    let slots = &records[0]["gt_answer"];
    let r = browser
        .post_json(
            &format!("/annotate/mini/{}/submit", items[0]),
            Some(&csrf_alice),
            &json!({"slots": slots, "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let r = browser
        .post_form(
            &format!("/annotate/mini/{}/skip", items[1]),
            &[
                ("csrf", &csrf_alice),
                ("reason", "blurry"),
                ("action", "flag"),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);

    // From the command line, as the operator.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = enact_hub()
        .env("ENACT_HUB_OPERATOR", "night-shift")
        .args(["backup", "--db"])
        .arg(server.db_path())
        .arg("--out")
        .arg(dir.path().join("snap.db"))
        .output()
        .expect("run");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let all = audit_cli(&server, &["--limit", "1000"]);
    assert_eq!(
        actions(&all),
        [
            "annotation.answer",
            "annotation.skip",
            "annotator.create",
            "assignment.change",
            "backup.create",
            "dataset.answer_visibility",
            "dataset.import",
            // The signing key, made for the submission's statement.
            "key.generate",
            "submission.create",
            "submission.listing",
            "token.issue",
            "token.revoke",
        ]
        .map(str::to_owned)
        .into_iter()
        .collect()
    );
    // Newest first, each with its actor.
    let ids: Vec<i64> = all.iter().map(|e| e["id"].as_i64().expect("id")).collect();
    assert!(ids.windows(2).all(|w| w[0] > w[1]), "{ids:?}");
    let by = |e: &Value| {
        format!(
            "{} {}",
            e["actor_kind"].as_str().unwrap(),
            e["actor"].as_str().unwrap()
        )
    };
    let issued = entry(&all, "token.issue", Some(&format!("token {prefix}")));
    assert_eq!(by(issued), "account boss");
    assert!(
        issued["detail"]
            .as_str()
            .unwrap()
            .contains("account team (submitter); daily quota 3")
    );
    let sub = entry(&all, "submission.create", None);
    assert_eq!(by(sub), "account team");
    assert_eq!(sub["target"], format!("submission {submission}"));
    assert_eq!(sub["dataset"], "mini");
    assert_eq!(sub["detail"], "model m1");
    let listing = entry(&all, "submission.listing", None);
    assert_eq!(by(listing), "account boss");
    assert_eq!(listing["detail"], "baseline true, visibility hidden");
    assert_eq!(
        entry(&all, "dataset.answer_visibility", None)["detail"],
        "answers public"
    );
    assert_eq!(by(entry(&all, "token.revoke", None)), "account boss");
    assert_eq!(by(entry(&all, "annotator.create", None)), "annotator root");
    let assigned = entry(&all, "assignment.change", None);
    assert_eq!(assigned["target"], "annotators alice");
    assert_eq!(
        assigned["detail"],
        "listed items: 2 asked, 2 new to the queues"
    );
    let answered = entry(&all, "annotation.answer", None);
    assert_eq!(by(answered), "annotator alice");
    assert_eq!(answered["target"], format!("item {}", items[0]));
    assert_eq!(
        entry(&all, "annotation.skip", None)["detail"],
        "flagged: blurry"
    );
    assert_eq!(
        by(entry(&all, "backup.create", None)),
        "operator night-shift"
    );
    assert_eq!(by(entry(&all, "dataset.import", None)), "operator tests");

    // Filters.
    assert_eq!(
        actions(&audit_cli(&server, &["--action", "token"])),
        ["token.issue".to_owned(), "token.revoke".to_owned()].into()
    );
    let alice_only = audit_cli(&server, &["--actor", "alice"]);
    assert_eq!(alice_only.len(), 2);
    let mini = audit_cli(&server, &["--dataset", "mini", "--limit", "1000"]);
    assert!(mini.iter().all(|e| e["dataset"] == "mini"));
    assert_eq!(audit_cli(&server, &["--limit", "3"]).len(), 3);
    assert!(audit_cli(&server, &["--since", "2999-01-01"]).is_empty());
    let out = enact_hub()
        .args(["audit", "--since", "yesterday", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("`since`"));
    let table = enact_hub()
        .args(["audit", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    let table = String::from_utf8_lossy(&table.stdout);
    assert!(table.starts_with("at "), "{table}");
    assert!(table.contains("operator tests") && table.contains("dataset.import"));
    assert!(table.contains("operator night-shift") && table.contains("backup.create"));

    // The admin page shows and filters the same entries.
    let (status, html) = root.text("/admin/audit?action=annotation").await;
    assert_eq!(status, StatusCode::OK);
    assert!(html.contains("annotation.answer") && html.contains("flagged: blurry"));
    assert!(!html.contains("<code>token.issue</code>"), "filtered out");
    let (status, html) = root.text("/admin/audit?action=nonsense").await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert!(html.contains("action"), "{html}");
    let (status, _) = browser.text("/admin/audit").await;
    assert_eq!(
        status,
        StatusCode::FORBIDDEN,
        "annotators do not read the log"
    );

    // The report bundle carries the dataset's entries.
    let audit_csv = report_bundle(&mut root, "mini", "?bootstrap=0")
        .await
        .into_iter()
        .find(|(path, _)| path.ends_with("/audit.csv"))
        .map(|(_, text)| text)
        .expect("audit.csv in the bundle");
    assert!(audit_csv.contains("\nid,at,actor_kind,actor,action,target,dataset,detail\n"));
    assert!(audit_csv.contains(&format!(
        "submission.create,submission {submission},mini,model m1"
    )));
    assert!(
        !audit_csv.contains("token.issue"),
        "only the dataset's entries"
    );
    server.stop().await;
}
