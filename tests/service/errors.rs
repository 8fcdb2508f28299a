//! Error analysis through the service and the command line: on ENACT's parity items (scene
//! graphs imported), a submission's `/errors` JSON is the one `enact-hub errors --json` prints
//! for the same file; examples follow the dataset's answer visibility; only the owner or an
//! admin reads a submission's analysis; the pages draw every row, the Human row included.

use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

fn check_identities(v: &Value) {
    let c = &v["components"];
    let s = &v["structural"];
    let n = |x: &Value| x.as_u64().unwrap();
    let paired = n(&s["polarity_inversion"])
        + n(&s["predicate_substitution"])
        + n(&s["entity_substitution"]);
    assert_eq!(
        n(&c["matched"]) + paired + n(&s["omission"]),
        n(&c["truth"])
    );
    assert_eq!(
        n(&c["matched"]) + paired + n(&s["hallucination"]),
        n(&c["predicted"])
    );
}

/// `GET /api/v1/submissions/{id}/errors` as `token`, expecting `status`; the body.
async fn errors_of(server: &TestServer, id: i64, token: &str, status: u16) -> Value {
    server
        .call(Method::GET, &format!("/api/v1/submissions/{id}/errors"))
        .bearer(token)
        .expect(status)
        .await
        .json()
}

#[tokio::test]
async fn the_api_and_the_cli_agree_on_parity_predictions() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let replayed = parity.join("replayed_activities");
    let server = spawn_app_with(|pool, _| {
        let parity = parity.clone();
        let replayed = replayed.clone();
        async move {
            let mut options = options("parity");
            options.scene_graphs = Some(replayed);
            import(&pool, &parity, &options).await;
        }
    })
    .await;
    let (_, admin) = api_token(&server.pool, "admin", Role::Admin, None, None).await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, other) = api_token(&server.pool, "other", Role::Submitter, None, None).await;

    for model in ["random", "adjswap", "length"] {
        let file = parity.join(format!("predictions/enact_ordering_{model}.jsonl"));
        let body = std::fs::read(&file).unwrap();
        let reply = submit_to(&server, "parity", &format!("model={model}"), &team, body).await;
        assert_eq!(reply.status, 201, "{model}: {}", reply.text);
        let id = reply.id();

        // Hidden answers (the default): aggregate figures only, and why.
        let hidden = errors_of(&server, id, &team, 200).await;
        assert_eq!(hidden["examples"], json!([]), "{model}");
        assert!(
            hidden["examples_withheld"]
                .as_str()
                .unwrap()
                .contains("hidden")
        );
        check_identities(&hidden);
        check_identities(&hidden["by_direction"]["forward"]);
        check_identities(&hidden["by_direction"]["inverse"]);
        errors_of(&server, id, &other, 404).await;

        server
            .call(Method::PUT, "/api/v1/admin/datasets/parity/answers")
            .bearer(&admin)
            .json(&json!({"answers": "public"}))
            .expect(200)
            .await;
        let public = errors_of(&server, id, &team, 200).await;
        server
            .call(Method::PUT, "/api/v1/admin/datasets/parity/answers")
            .bearer(&admin)
            .json(&json!({"answers": "hidden"}))
            .expect(200)
            .await;

        let out = enact_hub()
            .args(["errors", file.to_str().unwrap(), "--db"])
            .arg(server.db_path())
            .args(["--dataset", "parity", "--json"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let cli: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(cli, public, "{model}: CLI and API differ");
        if model == "length" {
            // Every answer of this file has another length than its item's.
            assert_eq!(public["excluded_unequal_length"], 96, "{public:#}");
        } else {
            assert!(
                public["analysed_answers"].as_u64().unwrap() > 80,
                "{model}: {public:#}"
            );
            assert!(
                !public["examples"].as_array().unwrap().is_empty(),
                "{model}"
            );
        }
        let mut without = public.clone();
        without["examples"] = json!([]);
        let mut hidden = hidden.clone();
        hidden.as_object_mut().unwrap().remove("examples_withheld");
        assert_eq!(hidden, without, "{model}: hiding changes only the examples");
    }

    // The comparison: every published row, in board order, as JSON and as pages.
    let compared = server.get_json("/api/v1/datasets/parity/errors").await.1;
    let rows = compared["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r["analysis"]["examples"] == json!([])));
    let page = server.get("/leaderboard/parity/errors").await;
    assert_eq!(page.status(), 200);
    let html = page.text().await.unwrap();
    for model in ["random", "adjswap", "length"] {
        assert!(
            html.contains(model),
            "{model} missing from the comparison page"
        );
    }
    assert!(html.contains("<svg") && html.contains("Polarity inversion"));
    let first = rows[0]["submission"].as_i64().unwrap();
    let row_page = server
        .get(&format!("/leaderboard/parity/errors/{first}"))
        .await;
    assert_eq!(row_page.status(), 200);
    let html = row_page.text().await.unwrap();
    assert!(
        html.contains("are hidden"),
        "examples of a hidden dataset are withheld"
    );
    assert_eq!(
        server
            .get("/leaderboard/parity/errors/human")
            .await
            .status(),
        404,
        "no human has answered"
    );
    assert_eq!(
        server
            .get_json("/api/v1/datasets/parity/errors?top=0")
            .await
            .0,
        400
    );
    assert_eq!(server.get_json("/api/v1/datasets/nope/errors").await.0, 404);
    server.stop().await;
}

#[tokio::test]
async fn the_cli_names_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    let predictions = dir.path().join("p.jsonl");
    std::fs::write(&predictions, answers(&records, &[0, 1])).unwrap();

    let out = enact_hub()
        .args(["errors", predictions.to_str().unwrap(), "--data"])
        .arg(&root)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8(out.stdout).unwrap();
    assert!(table.contains("answers analysed"), "{table}");
    assert!(table.contains("polarity inversion"), "{table}");

    let db = dir.path().join("x.db");
    let out = enact_hub()
        .args(["errors", predictions.to_str().unwrap(), "--db"])
        .arg(&db)
        .args(["--dataset", "missing"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("missing"), "{err}");

    std::fs::write(&predictions, "{\"id\": \"nope\", \"answer\": \"[1, 2]\"}\n").unwrap();
    let out = enact_hub()
        .args(["errors", predictions.to_str().unwrap(), "--data"])
        .arg(&root)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 1") && err.contains("nope"), "{err}");
}

#[tokio::test]
async fn a_stored_analysis_is_redone_when_scene_graphs_arrive() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let server = spawn_app_with(|pool, _| {
        let parity = parity.clone();
        async move {
            import(&pool, &parity, &options("parity")).await;
        }
    })
    .await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let body = std::fs::read(parity.join("predictions/enact_ordering_random.jsonl")).unwrap();
    let reply = submit_to(&server, "parity", "model=random", &team, body).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let id = reply.id();
    let before = errors_of(&server, id, &team, 200).await;
    // Without scene graphs forward answers cannot be compared; inverse ones use the sets
    // parsed from the action sentences.
    let forward = &before["by_direction"]["forward"];
    assert_eq!(forward["analysed_answers"], 0, "{forward:#}");
    assert!(forward["excluded_without_signatures"].as_u64().unwrap() > 0);
    assert!(
        before["by_direction"]["inverse"]["analysed_answers"]
            .as_u64()
            .unwrap()
            > 0
    );

    let mut with_graphs = options("parity");
    with_graphs.scene_graphs = Some(parity.join("replayed_activities"));
    import(&server.pool, &parity, &with_graphs).await;
    let after = errors_of(&server, id, &team, 200).await;
    assert!(
        after["by_direction"]["forward"]["analysed_answers"]
            .as_u64()
            .unwrap()
            > 0,
        "the stored analysis was not redone"
    );
    server.stop().await;
}

#[tokio::test]
async fn the_cli_analyses_one_annotator_at_a_time() {
    use enact_hub::app::Hub;
    use enact_hub::core::annotation::{Draft, InteractionCounts, Session};

    let (server, records) = spawn_app_with_release().await;
    let hub = Hub::from(server.pool.clone());
    let ann = crate::annotate::annotator(&server, "ann", false).await;
    let bob = crate::annotate::annotator(&server, "bob", false).await;
    let ids: Vec<&str> = records[..3]
        .iter()
        .map(|r| r["id"].as_str().expect("id"))
        .collect();
    crate::annotate::assign(&server, ann, &ids).await;
    crate::annotate::assign(&server, bob, &ids[..1]).await;
    for (annotator, name, count) in [(ann, "ann", 3), (bob, "bob", 1)] {
        let session = Session {
            annotator,
            name: name.to_owned(),
            is_admin: false,
            csrf_token: String::new(),
        };
        for record in &records[..count] {
            let slots = record["gt_answer"]
                .as_array()
                .expect("gt")
                .iter()
                .map(|l| Some(l.as_u64().expect("label") as u8))
                .collect();
            let draft = Draft {
                slots,
                counts: InteractionCounts::default(),
                history: Vec::new(),
            };
            let id = record["id"].as_str().expect("id");
            enact_hub::app::annotation::answer(&hub, &session, "mini", id, &draft)
                .await
                .expect("answered");
        }
    }
    let analyse = |name: &str| {
        enact_hub()
            .args([
                "errors",
                "--annotator",
                name,
                "--dataset",
                "mini",
                "--json",
                "--db",
            ])
            .arg(server.db_path())
            .output()
            .expect("run")
    };
    for (name, answers) in [("ann", 3), ("bob", 1)] {
        let out = analyse(name);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: Value = serde_json::from_slice(&out.stdout).expect("json");
        let counted = ["analysed_answers", "excluded_without_signatures"]
            .iter()
            .map(|k| v[*k].as_u64().expect("count"))
            .sum::<u64>();
        assert_eq!(counted, answers, "{name}: {v:#}");
        assert_eq!(v["errors"], 0, "ground-truth answers have no errors");
    }
    let out = analyse("nobody");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no annotator named 'nobody'"));
    server.stop().await;
}
