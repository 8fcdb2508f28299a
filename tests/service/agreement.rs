//! Agreement on stored annotations: `enact-hub agreement --db`, the cross-annotation protocol,
//! and the report over HTTP and on the command line, checked against the pure core.

use enact_hub::core::agreement::{
    AnnotatedOrdering, BootstrapConfig, OrderingAnnotations, OrderingEncoding, ordering_agreement,
};
use enact_hub::core::annotation::{Outcome, Telemetry};
use enact_hub::core::credentials::{random_token as new_token, token_hash};
use enact_hub::core::verifier::Permutation;
use enact_hub::store;
use serde_json::Value;

use crate::annotate::{Browser, annotator, logged_in_on};
use crate::helpers::*;

const TELEMETRY: Telemetry = Telemetry {
    time_on_item_ms: 1000,
    time_to_first_placement_ms: Some(10),
    placements: 2,
    swaps: 0,
    clears: 0,
    undos: 0,
};

/// A database with dataset "mini" (one forward and one inverse item for L = 3, 4, 5) and
/// answers stored directly: `answers[a][i]` is annotator `a`'s answer to item `i`.
async fn stored_answers(
    dir: &tempfile::TempDir,
    answers: &[Vec<Option<Vec<u8>>>],
) -> (std::path::PathBuf, Vec<String>) {
    let (pool, db) = fresh_db_located(dir).await;
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4, 5]);
    import(&pool, &root, &options("mini")).await;
    let ids: Vec<String> = records
        .iter()
        .map(|r| r["id"].as_str().expect("id").to_owned())
        .collect();
    let mut conn = pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, "mini")
        .await
        .expect("query")
        .expect("mini");
    let rows = store::annotations::item_rowids(&mut conn, dataset.id, &ids)
        .await
        .expect("query")
        .into_iter()
        .collect::<Option<Vec<i64>>>()
        .expect("ids");
    drop(conn);
    let mut conn = write_tx(&pool).await;
    for (a, row) in answers.iter().enumerate() {
        let annotator = store::annotations::create_annotator(
            &mut conn,
            &format!("coder{a}"),
            false,
            &token_hash(&new_token()),
        )
        .await
        .expect("insert");
        for (item, answer) in row.iter().enumerate() {
            let Some(answer) = answer else { continue };
            let outcome = Outcome::Answered(Permutation::new(answer.clone()).expect("perm"));
            store::annotations::finish(&mut conn, annotator, rows[item], &outcome, &TELEMETRY)
                .await
                .expect("finish");
        }
    }
    conn.commit().await.expect("commit");
    pool.close().await;
    (db, ids)
}

fn run_json(args: &[&str]) -> (bool, Value, String) {
    let out = enact_hub().args(args).output().expect("run enact-hub");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let json = if out.status.success() {
        serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON: {e}: {stdout}"))
    } else {
        Value::Null
    };
    (out.status.success(), json, stderr)
}

/// `enact-hub agreement --db db --dataset mini` with `args` besides (see [`run_json`]).
fn agreement_on_mini(db: &str, args: &[&str]) -> (bool, Value, String) {
    let mut all = vec!["agreement", "--db", db, "--dataset", "mini"];
    all.extend_from_slice(args);
    run_json(&all)
}

fn close(a: &Value, b: Option<f64>) {
    match (a.as_f64(), b) {
        (Some(a), Some(b)) => assert!((a - b).abs() < 1e-12, "{a} != {b}"),
        (None, None) => {}
        (a, b) => panic!("{a:?} != {b:?}"),
    }
}

/// The answers of [`stored_answers`] (three coders) as the pure core takes them: the items
/// `keep` keeps of those answered by two or more, sorted by id.
fn core_annotations(
    ids: &[String],
    answers: &[Vec<Option<Vec<u8>>>],
    keep: impl Fn(usize) -> bool,
) -> OrderingAnnotations {
    let mut items: Vec<AnnotatedOrdering> = ids
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(i, id)| AnnotatedOrdering {
            item_id: id.clone(),
            answers: answers.iter().map(|row| row[i].clone()).collect(),
        })
        .filter(|item| item.answers.iter().flatten().count() >= 2)
        .collect();
    items.sort_by(|a, b| a.item_id.cmp(&b.item_id));
    let names = vec!["coder0".into(), "coder1".into(), "coder2".into()];
    OrderingAnnotations::new(names, items).expect("valid")
}

#[tokio::test]
async fn agreement_on_stored_annotations_matches_the_core() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Items in release order: F3, I3, F4, I4, F5, I5 (answer lengths 2, 2, 3, 3, 4, 4).
    let some = |v: &[u8]| Some(v.to_vec());
    let answers = vec![
        vec![
            some(&[2, 1]),
            some(&[1, 2]),
            some(&[3, 2, 1]),
            some(&[1, 2, 3]),
            some(&[4, 3, 2, 1]),
            None,
        ],
        vec![
            some(&[2, 1]),
            some(&[2, 1]),
            some(&[3, 2, 1]),
            some(&[1, 3, 2]),
            None,
            some(&[1, 2, 3, 4]),
        ],
        vec![
            some(&[2, 1]),
            some(&[1, 2]),
            None,
            some(&[1, 2, 3]),
            some(&[4, 3, 1, 2]),
            None,
        ],
    ];
    let (db, ids) = stored_answers(&dir, &answers).await;
    let db = db.to_str().expect("utf-8 path");

    let core = core_annotations(&ids, &answers, |_| true);
    assert_eq!(core.items().len(), 5, "I5 has one answer only");

    for encoding in OrderingEncoding::ALL {
        let (ok, json, stderr) = agreement_on_mini(
            db,
            &[
                "--encoding",
                encoding.name(),
                "--bootstrap",
                "300",
                "--seed",
                "9",
                "--confidence",
                "0.9",
            ],
        );
        assert!(ok, "{stderr}");
        let config = BootstrapConfig {
            replicates: 300,
            confidence_level: 0.9,
            seed: 9,
        };
        let expected = ordering_agreement(&core, encoding, &config).expect("core");
        assert_eq!(json["encoding"], encoding.name());
        assert_eq!(json["level"], expected.level.name());
        assert_eq!(json["metric_version"], "enact-hub-agreement-report/1");
        assert_eq!(json["hub"]["version"], env!("CARGO_PKG_VERSION"));
        assert_eq!(json["dataset_hash"].as_str().expect("hash").len(), 64);
        close(&json["alpha"], expected.alpha.estimate.alpha);
        close(&json["ci"]["low"], expected.alpha.ci_low);
        close(&json["ci"]["high"], expected.alpha.ci_high);
        assert_eq!(json["ci"]["seed"], 9);
        assert_eq!(json["ci"]["replicates"], 300);
        assert_eq!(json["ci"]["confidence_level"], 0.9);
        let pairs = json["pairwise"].as_array().expect("pairs");
        assert_eq!(pairs.len(), 3);
        for (pair, want) in pairs.iter().zip(&expected.pairwise) {
            close(&pair["alpha"], want.result.alpha);
            assert_eq!(pair["a"]["name"], format!("coder{}", want.coder_a));
            assert_eq!(pair["b"]["name"], format!("coder{}", want.coder_b));
        }
        // F3 and I4 agree all round; I3, F4, F5 do not.
        assert_eq!(json["exact_agreement"]["agreeing_items"], 2);
        assert_eq!(json["exact_agreement"]["compared_items"], 5);
        assert_eq!(json["counts"]["items"], 5);
        assert_eq!(json["counts"]["answers"], 13);
        assert_eq!(json["counts"]["annotators"], 3);
    }

    // Without an interval the CI is null; a level the encoding cannot take is refused.
    let (ok, json, _) = agreement_on_mini(
        db,
        &[
            "--encoding",
            "rank",
            "--bootstrap",
            "0",
            "--level",
            "interval",
        ],
    );
    assert!(ok);
    assert_eq!(json["level"], "interval");
    assert!(json["ci"].is_null());
    let (ok, _, stderr) = agreement_on_mini(db, &["--encoding", "answer", "--level", "ordinal"]);
    assert!(!ok);
    assert!(
        stderr.contains("only the nominal level applies"),
        "{stderr}"
    );
    let (ok, _, stderr) = run_json(&["agreement", "--db", db, "--dataset", "nope"]);
    assert!(!ok);
    assert!(stderr.contains("no dataset named 'nope'"), "{stderr}");
}

#[tokio::test]
async fn agreement_without_overlapping_answers_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let answers = vec![vec![Some(vec![2, 1]), None], vec![None, Some(vec![1, 2])]];
    let (db, _) = stored_answers(&dir, &answers).await;
    let (ok, _, stderr) = run_json(&[
        "agreement",
        "--db",
        db.to_str().expect("utf-8"),
        "--dataset",
        "mini",
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("no item has answers from two or more annotators (2 answers on 2 items)"),
        "{stderr}"
    );
}

async fn logged_in(server: &TestServer, name: &str) -> (Browser, String) {
    logged_in_on(server, name, "/annotate").await
}

async fn kinds(server: &TestServer) -> Vec<(i64, String, String)> {
    db!(
        server.pool,
        fetch_all,
        sqlx::query_as(
            "SELECT g.annotator, i.item_id, g.kind FROM assignments g \
             JOIN items i ON i.id = g.item ORDER BY g.annotator, i.item_id",
        )
    )
    .expect("assignments")
}

#[tokio::test]
async fn the_protocol_runs_once_with_csrf_and_cross_assigns_blind() {
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        write_balanced_release(&root, &[3, 4], 4);
        import(&pool, &root, &options("mini")).await;
    })
    .await;
    annotator(&server, "root", true).await;
    let ids: Vec<i64> = [
        annotator(&server, "ann", false).await,
        annotator(&server, "bob", false).await,
    ]
    .to_vec();
    let (mut admin, csrf) = logged_in(&server, "root").await;
    let mut fields = vec![
        ("csrf", csrf.as_str()),
        ("dataset", "mini"),
        ("mode", "split"),
    ];
    let id_text: Vec<String> = ids.iter().map(i64::to_string).collect();
    for id in &id_text {
        fields.push(("annotator", id));
    }
    assert_eq!(
        admin.post_form("/admin/assign", &fields).await.status(),
        200
    );
    // Each answers their whole primary share (ground truth is the reversed order).
    for name in ["ann", "bob"] {
        let (mut browser, token) = logged_in(&server, name).await;
        let queue = store::annotations::queue(
            &mut server.pool.acquire().await.expect("conn"),
            ids[usize::from(name == "bob")],
        )
        .await
        .expect("queue");
        assert_eq!(queue.len(), 8);
        for entry in queue {
            let slots: Vec<u8> = (1..entry.step_length.get()).rev().collect();
            let path = format!("/annotate/mini/{}", entry.item_id);
            browser.get(&path).await;
            let r = browser
                .post_json(
                    &format!("{path}/submit"),
                    Some(&token),
                    &serde_json::json!({"slots": slots, "counts": {"placements": 1, "swaps": 0, "clears": 0, "undos": 0}}),
                )
                .await;
            assert_eq!(r.status(), 200);
        }
    }
    let path = "/admin/datasets/mini/agreement-protocol";
    let r = admin
        .post_form(path, &[("items_per_cell", "1"), ("seed", "5")])
        .await;
    assert_eq!(r.status(), 403, "no CSRF token, no protocol");
    let r = admin
        .post_form(
            path,
            &[("csrf", &csrf), ("items_per_cell", "1"), ("seed", "5")],
        )
        .await;
    assert_eq!(r.status(), 200);
    let html = r.text().await.expect("body");
    assert!(
        html.contains("drew 8 items (k = 1, seed = 5) from the completed primary items of 2 annotators and added 8 assignments"),
        "{html}"
    );
    let stored = kinds(&server).await;
    let cross: Vec<&(i64, String, String)> = stored
        .iter()
        .filter(|(_, _, kind)| kind == "agreement")
        .collect();
    assert_eq!(cross.len(), 8);
    assert_eq!(stored.len(), 16 + 8);
    // Each cross-assigned item is the other annotator's primary item.
    for (who, item, _) in &cross {
        assert!(
            stored
                .iter()
                .any(|(other, it, kind)| other != who && it == item && kind == "primary")
        );
    }
    // Each annotator's cross-assignments follow its primary queue, numbered on from its end.
    for id in &ids {
        let of = |what: &str, kind: &str| {
            format!("SELECT {what} FROM assignments WHERE annotator = {id} AND kind = '{kind}'")
        };
        assert_eq!(
            count(&server.pool, &of("max(position)", "primary")).await,
            8
        );
        assert_eq!(
            count(&server.pool, &of("min(position)", "agreement")).await,
            9
        );
        assert_eq!(
            count(&server.pool, &of("max(position)", "agreement")).await,
            12
        );
        assert_eq!(count(&server.pool, &of("count(*)", "agreement")).await, 4);
    }
    // The annotator's queue and item page look like any other assignment.
    let (mut ann, _) = logged_in(&server, "ann").await;
    let (_, queue) = ann.text("/annotate").await;
    assert!(!queue.to_lowercase().contains("agreement"), "{queue}");
    let theirs = cross
        .iter()
        .find(|(who, _, _)| *who == ids[0])
        .expect("ann has one");
    let (status, page) = ann.text(&format!("/annotate/mini/{}", theirs.1)).await;
    assert_eq!(status, 200);
    assert!(!page.to_lowercase().contains("agreement"), "{page}");
    // A second run is refused and changes nothing, over HTTP and on the command line.
    let r = admin
        .post_form(path, &[("csrf", &csrf), ("items_per_cell", "2")])
        .await;
    assert_eq!(r.status(), 409);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("already ran on this dataset")
    );
    let out = enact_hub()
        .args(["agreement-protocol", "--dataset", "mini", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("seed = 5"));
    assert_eq!(kinds(&server).await, stored);
    server.stop().await;
}

/// The answer `who` gives to an item whose ground truth is L−1..1: mostly right, with the
/// first two labels swapped on some items so that annotators disagree.
fn answer_of(who: usize, item_id: &str, length: u8) -> Vec<u8> {
    let mut labels: Vec<u8> = (1..length).rev().collect();
    let spread: usize = item_id.bytes().map(usize::from).sum();
    if (spread + who).is_multiple_of(6) {
        labels.swap(0, 1);
    }
    labels
}

/// Answers every item still to do in `name`'s queue over HTTP; records what was sent.
async fn answer_queue(
    server: &TestServer,
    who: usize,
    name: &str,
    annotator_id: i64,
    sent: &mut Vec<(String, usize, Vec<u8>)>,
) -> usize {
    let (mut browser, token) = logged_in(server, name).await;
    let queue = store::annotations::queue(
        &mut server.pool.acquire().await.expect("conn"),
        annotator_id,
    )
    .await
    .expect("queue");
    let mut answered = 0;
    for entry in queue.iter().filter(|e| e.finished.is_none()) {
        let labels = answer_of(who, &entry.item_id, entry.step_length.get());
        let path = format!("/annotate/mini/{}", entry.item_id);
        let (status, _) = browser.text(&path).await;
        assert_eq!(status, 200, "{name} opens {path}");
        let r = browser
            .post_json(
                &format!("{path}/submit"),
                Some(&token),
                &serde_json::json!({"slots": labels, "counts": {"placements": 3, "swaps": 0, "clears": 0, "undos": 0}}),
            )
            .await;
        assert_eq!(r.status(), 200, "{name} submits {path}");
        sent.push((entry.item_id.clone(), who, labels));
        answered += 1;
    }
    answered
}

#[tokio::test]
async fn end_to_end_primary_split_protocol_answers_and_report() {
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        write_balanced_release(&root, &[3, 4], 3);
        import(&pool, &root, &options("mini")).await;
    })
    .await;
    annotator(&server, "root", true).await;
    let names = ["ann", "bob", "cat"];
    let mut ids = Vec::new();
    for name in names {
        ids.push(annotator(&server, name, false).await);
    }
    let (mut admin, csrf) = logged_in(&server, "root").await;

    // Primary: a balanced split of the 12 items, one per direction × L for each annotator.
    let id_text: Vec<String> = ids.iter().map(i64::to_string).collect();
    let mut fields = vec![
        ("csrf", csrf.as_str()),
        ("dataset", "mini"),
        ("mode", "split"),
    ];
    for id in &id_text {
        fields.push(("annotator", id));
    }
    assert_eq!(
        admin.post_form("/admin/assign", &fields).await.status(),
        200
    );
    let mut sent = Vec::new();
    for (who, name) in names.iter().enumerate() {
        assert_eq!(
            answer_queue(&server, who, name, ids[who], &mut sent).await,
            4
        );
    }

    // A page's bootstrap stays bounded, and the refusal names the parameter and its range.
    let (status, body) = admin_json(
        &mut admin,
        "/admin/datasets/mini/report.json?bootstrap=20001",
    )
    .await;
    assert_eq!(status, 400);
    assert_eq!(body["code"], "bad_value_whole_number", "{body}");
    assert_eq!(
        body["details"],
        serde_json::json!({"field": "bootstrap", "value": "20001", "least": 0, "most": 20000})
    );

    // Before the protocol there is nothing to agree on, and the report says so.
    let (status, body) =
        admin_json(&mut admin, "/admin/datasets/mini/report.json?bootstrap=50").await;
    assert_eq!(status, 200);
    assert!(body["agreement"].is_null());
    assert!(
        body["agreement_unavailable"]
            .as_str()
            .expect("why")
            .contains("no item has answers")
    );

    // The protocol: k = 1 per annotator × direction × L, each item to the two others.
    let r = admin
        .post_form(
            "/admin/datasets/mini/agreement-protocol",
            &[("csrf", &csrf), ("items_per_cell", "1"), ("seed", "3")],
        )
        .await;
    assert_eq!(r.status(), 200);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("drew 12 items (k = 1, seed = 3)")
    );
    for (who, name) in names.iter().enumerate() {
        assert_eq!(
            answer_queue(&server, who, name, ids[who], &mut sent).await,
            8
        );
    }
    assert_eq!(sent.len(), 12 + 24);

    // A model submission for the comparisons.
    let token = api_token(
        &server.pool,
        "team",
        enact_hub::core::credentials::Role::Submitter,
        None,
        None,
    )
    .await
    .1;
    let mut item_ids: Vec<String> = sent.iter().map(|(item, _, _)| item.clone()).collect();
    item_ids.sort();
    item_ids.dedup();
    let body: String = item_ids
        .iter()
        .map(|id| {
            let length = sent
                .iter()
                .find(|(i, _, _)| i == id)
                .map_or(0, |s| s.2.len());
            let answer: Vec<usize> = (1..=length).collect();
            format!("{}\n", serde_json::json!({"id": id, "answer": answer}))
        })
        .collect();
    let reply = submit_to(&server, "mini", "model=ascending", &token, body).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let submission = reply.id();

    // The pure core on exactly what was submitted.
    let mut items: Vec<AnnotatedOrdering> = item_ids
        .iter()
        .map(|id| AnnotatedOrdering {
            item_id: id.clone(),
            answers: (0..3)
                .map(|who| {
                    sent.iter()
                        .find(|(item, w, _)| item == id && *w == who)
                        .map(|(_, _, labels)| labels.clone())
                })
                .collect(),
        })
        .filter(|item| item.answers.iter().flatten().count() >= 2)
        .collect();
    items.sort_by(|a, b| a.item_id.cmp(&b.item_id));
    assert_eq!(items.len(), 12, "every sampled item has three answers");
    assert!(items.iter().all(|i| i.answers.iter().all(Option::is_some)));
    let core = OrderingAnnotations::new(names.iter().map(|n| (*n).to_owned()).collect(), items)
        .expect("valid");
    let config = BootstrapConfig {
        replicates: 400,
        confidence_level: 0.95,
        seed: 4,
    };
    let expected = ordering_agreement(&core, OrderingEncoding::Answer, &config).expect("core");
    let exact = core.exact_agreement();
    assert!(
        exact.agreeing_items < 12 && exact.agreeing_items > 0,
        "{exact:?}"
    );

    // The report over HTTP.
    let query = "?bootstrap=400&seed=4&encoding=answer";
    let (status, report) = admin_json(
        &mut admin,
        &format!("/admin/datasets/mini/report.json{query}"),
    )
    .await;
    assert_eq!(status, 200, "{report}");
    let agreement = &report["agreement"];
    assert_eq!(agreement["items"], 12);
    assert_eq!(agreement["answers"], 36);
    close(
        &agreement["alpha"]["estimate"]["alpha"],
        expected.alpha.estimate.alpha,
    );
    close(&agreement["alpha"]["ci_low"], expected.alpha.ci_low);
    close(&agreement["alpha"]["ci_high"], expected.alpha.ci_high);
    let pairs = agreement["pairwise"].as_array().expect("pairs");
    assert_eq!(pairs.len(), 3);
    for (pair, want) in pairs.iter().zip(&expected.pairwise) {
        close(&pair["alpha"], want.result.alpha);
        assert_eq!(pair["a"]["name"], names[want.coder_a]);
        assert_eq!(pair["b"]["name"], names[want.coder_b]);
    }
    assert_eq!(
        agreement["exact_agreement"]["agreeing_items"],
        exact.agreeing_items
    );
    assert_eq!(agreement["exact_agreement"]["compared_items"], 12);
    let counts = agreement["counts"].as_array().expect("counts");
    assert_eq!(counts.len(), 4, "forward and inverse × L = 3, 4");
    assert!(counts.iter().all(|c| c["items"] == 3 && c["answers"] == 9));
    let stamp = &report["stamp"];
    assert_eq!(stamp["bootstrap_seed"], 4);
    assert_eq!(stamp["submission_ids"], serde_json::json!([submission]));
    assert_eq!(stamp["annotator_ids"], serde_json::json!(ids));
    assert_eq!(stamp["protocol"]["seed"], 3);
    assert_eq!(stamp["hub"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(stamp["hub"]["commit"], enact_hub::core::version::COMMIT);
    let rows = report["rows"].as_array().expect("rows");
    assert_eq!(rows.last().expect("human")["source"], "human");
    let comparison = &report["comparisons"][0];
    assert_eq!(comparison["a"]["submission"], submission);
    assert_eq!(comparison["b"]["label"], "Human");
    assert_eq!(comparison["cells"].as_array().expect("cells").len(), 16);
    assert!(comparison["items"].as_u64().expect("items") > 0);

    // The page and the bundle.
    let (status, html) = admin
        .text(&format!("/admin/datasets/mini/report{query}"))
        .await;
    assert_eq!(status, 200);
    assert!(
        html.contains(&format!(
            "{:.4}",
            expected.alpha.estimate.alpha.expect("alpha")
        )),
        "{html}"
    );
    assert!(html.contains("<svg") && html.contains("ascending (#"));
    let r = admin
        .get(&format!("/admin/datasets/mini/report.tar{query}"))
        .await;
    assert_eq!(r.status(), 200);
    assert_eq!(r.headers()["content-type"], "application/x-tar");
    let bytes = r.bytes().await.expect("tar");
    let mut archive = tar::Archive::new(bytes.as_ref());
    let hash = stamp["dataset_hash"].as_str().expect("hash").to_owned();
    let mut names_in_tar = Vec::new();
    for entry in archive.entries().expect("entries") {
        let mut entry = entry.expect("entry");
        let mut text = String::new();
        std::io::Read::read_to_string(&mut entry, &mut text).expect("utf-8");
        let path = entry.path().expect("path").display().to_string();
        assert!(text.contains(&hash), "{path} lacks the dataset hash");
        assert!(text.contains("enact-hub-agreement-report/1"), "{path}");
        if path.ends_with("/errors.json") {
            // One error analysis per published row, then the Human row.
            let errors: serde_json::Value = serde_json::from_str(&text).expect("errors.json");
            let rows = errors["rows"].as_array().expect("rows");
            assert_eq!(rows.last().expect("human")["label"], "Human");
            assert!(rows.iter().any(|r| r["submission"] == submission));
            assert!(rows.iter().all(|r| r["analysis"]["structural"].is_object()));
        }
        names_in_tar.push(path);
    }
    assert_eq!(names_in_tar.len(), 12);
    assert!(names_in_tar.iter().any(|n| n.ends_with("/errors.csv")));
    assert!(names_in_tar.iter().any(|n| n.ends_with("/audit.csv")));
    assert!(names_in_tar.iter().any(|n| n.ends_with("/tables.tex")));

    // Two submissions chosen by the admin: the ground truth itself against "ascending".
    let body: String = item_ids
        .iter()
        .map(|id| {
            let length = sent
                .iter()
                .find(|(i, _, _)| i == id)
                .map_or(0, |s| s.2.len());
            let answer: Vec<usize> = (1..=length).rev().collect();
            format!("{}\n", serde_json::json!({"id": id, "answer": answer}))
        })
        .collect();
    let reply = submit_to(&server, "mini", "model=oracle", &token, body).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let oracle = reply.id();
    let (status, chosen) = admin_json(
        &mut admin,
        &format!("/admin/datasets/mini/report.json?bootstrap=0&a={submission}&b={oracle}"),
    )
    .await;
    assert_eq!(status, 200, "{chosen}");
    let pair = chosen["comparisons"]
        .as_array()
        .expect("list")
        .last()
        .expect("pair")
        .clone();
    assert_eq!(pair["a"]["submission"], submission);
    assert_eq!(pair["b"]["submission"], oracle);
    assert!(
        pair["overall"]["delta"].as_f64().expect("delta") < 0.0,
        "{pair}"
    );
    assert_eq!(pair["overall"]["mean_b"], 1.0);
    let (status, error) = admin_json(
        &mut admin,
        &format!("/admin/datasets/mini/report.json?a={submission}&b=999"),
    )
    .await;
    assert_eq!(status, 400);
    assert!(
        error["error"]
            .as_str()
            .expect("msg")
            .contains("submission 999 is not a published")
    );
    let (status, _) = admin_json(&mut admin, "/admin/datasets/mini/report.json?a=1").await;
    assert_eq!(status, 400);

    // An annotator is refused the report; the command line writes the same files.
    let (mut ann, _) = logged_in(&server, "ann").await;
    assert_eq!(ann.get("/admin/datasets/mini/report").await.status(), 403);
    let out_dir = tempfile::tempdir().expect("out");
    let out = enact_hub()
        .args([
            "report",
            "--dataset",
            "mini",
            "--bootstrap",
            "400",
            "--seed",
            "4",
            "--db",
        ])
        .arg(server.db_path())
        .arg("--out")
        .arg(out_dir.path())
        .output()
        .expect("run report");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written: Value = serde_json::from_str(
        &std::fs::read_to_string(out_dir.path().join("report.json")).expect("report.json"),
    )
    .expect("json");
    assert_eq!(written["agreement"]["pairwise"], agreement["pairwise"]);
    assert_eq!(
        written["agreement"]["alpha"]["ci_low"],
        agreement["alpha"]["ci_low"]
    );
    assert!(
        std::fs::read_to_string(out_dir.path().join("agreement.csv"))
            .expect("csv")
            .starts_with("# dataset: mini\n")
    );
    server.stop().await;
}

async fn admin_json(browser: &mut Browser, path: &str) -> (reqwest::StatusCode, Value) {
    let r = browser.get(path).await;
    let status = r.status();
    (status, r.json().await.expect("json"))
}

/// Answers on gold items are left out of the agreement report: the coders agree on every
/// ordinary item (alpha 1) and disagree on the two gold ones, which would pull alpha down.
#[tokio::test]
async fn gold_answers_are_left_out_of_the_agreement_report() {
    let dir = tempfile::tempdir().expect("tempdir");
    let some = |v: &[u8]| Some(v.to_vec());
    // Items in release order: F3, I3, F4, I4, F5, I5; I3 and I5 are made gold.
    let answers = [
        ([1, 2], [1, 2, 3, 4]),
        ([2, 1], [4, 3, 2, 1]),
        ([1, 2], [1, 2, 4, 3]),
    ]
    .map(|(i3, i5)| {
        vec![
            some(&[2, 1]),
            some(&i3),
            some(&[3, 2, 1]),
            some(&[1, 2, 3]),
            some(&[4, 3, 2, 1]),
            some(&i5),
        ]
    })
    .to_vec();
    let gold = [1, 5];
    let (db, ids) = stored_answers(&dir, &answers).await;
    let db = db.to_str().expect("utf-8 path");
    let config = BootstrapConfig {
        replicates: 100,
        confidence_level: 0.95,
        seed: 1,
    };
    let alpha = |keep: &dyn Fn(usize) -> bool| {
        let core = core_annotations(&ids, &answers, keep);
        let report = ordering_agreement(&core, OrderingEncoding::Answer, &config).expect("core");
        report.alpha.estimate.alpha.expect("an alpha")
    };
    let with_gold = alpha(&|_| true);
    assert!(
        with_gold < 0.9,
        "the gold answers would give alpha {with_gold}"
    );
    assert_eq!(alpha(&|i| !gold.contains(&i)), 1.0);

    let list = dir.path().join("gold.txt");
    std::fs::write(&list, format!("{}\n{}\n", ids[gold[0]], ids[gold[1]])).expect("a list");
    let out = enact_hub()
        .args(["gold", "set", "mini", "--rate", "5", "--db", db, "--items"])
        .arg(&list)
        .output()
        .expect("run enact-hub");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (ok, json, stderr) = agreement_on_mini(db, &["--encoding", "answer", "--bootstrap", "0"]);
    assert!(ok, "{stderr}");
    close(&json["alpha"], Some(1.0));
    assert_eq!(json["counts"]["items"], 4, "{json}");
    assert_eq!(json["counts"]["answers"], 12, "{json}");
}
