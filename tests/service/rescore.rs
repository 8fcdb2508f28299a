//! Metric versions and rescoring: human verdicts stored when an answer is finished, results
//! of an older metric version marked on the leaderboard until `rescore` brings them to the
//! current one (audited, resumable, byte-identical when nothing changed), and the job form.

use std::sync::Mutex;

use enact_hub::app::jobs::{self, JobId, JobSettings, JobState, Worker};
use enact_hub::app::rescore::{
    self, RescoreJob, RescoreJobProgress, RescorePayload, RescoreProgress, RescoreStage,
};
use enact_hub::app::{self, AppError, Hub};
use enact_hub::core::annotation::{Draft, InteractionCounts, Session};
use enact_hub::core::audit::Actor;
use enact_hub::core::credentials::Role;
use enact_hub::core::leaderboard::RowSource;
use enact_hub::core::metric::METRIC_VERSION;
use enact_hub::store::Pool;
use serde_json::Value;

use crate::helpers::*;

type VerdictRow = (
    i64,
    Option<i64>,
    Option<String>,
    Option<String>,
    String,
    Option<String>,
    bool,
    bool,
    bool,
    Option<f64>,
);

type HumanVerdictRow = (
    i64,
    Option<bool>,
    Option<bool>,
    Option<bool>,
    Option<f64>,
    Option<i64>,
);

async fn scores_text(pool: &Pool, id: i64) -> String {
    db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, String>("SELECT scores FROM submissions WHERE id = $1").bind(id)
    )
    .expect("scores")
}

async fn verdict_rows(pool: &Pool, id: i64) -> Vec<VerdictRow> {
    db!(
        pool,
        fetch_all,
        sqlx::query_as::<_, VerdictRow>(
            "SELECT item, line, raw_answer, permutation, outcome, failure, exact_match, \
             semantic_match, task_accuracy, pairwise_accuracy FROM submission_items \
             WHERE submission = $1 ORDER BY item"
        )
        .bind(id)
    )
    .expect("verdicts")
}

async fn human_verdicts(pool: &Pool) -> Vec<HumanVerdictRow> {
    db!(
        pool,
        fetch_all,
        sqlx::query_as::<_, HumanVerdictRow>(
            "SELECT item, exact_match, semantic_match, task_accuracy, pairwise_accuracy, \
             metric_version FROM annotations WHERE outcome = 'answered' ORDER BY item"
        )
    )
    .expect("human verdicts")
}

/// "ann" answers the first `count` records through the annotation use case, the first one
/// wrongly (its ground truth reversed).
async fn annotate(server: &TestServer, records: &[Value], count: usize) {
    let hub = Hub::from(server.pool.clone());
    let ann = crate::annotate::annotator(server, "ann", false).await;
    let ids: Vec<&str> = records[..count]
        .iter()
        .map(|r| r["id"].as_str().expect("id"))
        .collect();
    crate::annotate::assign(server, ann, &ids).await;
    let session = Session {
        annotator: ann,
        name: "ann".to_owned(),
        is_admin: false,
        csrf_token: String::new(),
    };
    for (i, record) in records[..count].iter().enumerate() {
        let mut slots: Vec<Option<u8>> = record["gt_answer"]
            .as_array()
            .expect("gt")
            .iter()
            .map(|l| Some(l.as_u64().expect("label") as u8))
            .collect();
        if i == 0 {
            slots.reverse();
        }
        let draft = Draft {
            slots,
            counts: InteractionCounts::default(),
            history: Vec::new(),
        };
        app::annotation::answer(&hub, &session, "mini", ids[i], &draft)
            .await
            .expect("answered");
    }
}

/// Marks a submission's scores as computed with metric version 1, as a migration raising the
/// version would leave them.
async fn age(pool: &Pool, submission: i64) {
    db!(
        pool,
        execute,
        sqlx::query("UPDATE submissions SET metric_version = 1 WHERE id = $1").bind(submission)
    )
    .expect("age the submission");
}

fn operator() -> Actor {
    Actor::Operator("tester".to_owned())
}

/// The leaderboard as a hub with empty caches reads it from the store.
async fn board(pool: &Pool) -> Vec<enact_hub::core::leaderboard::LeaderboardRow> {
    app::leaderboard::of(&Hub::from(pool.clone()), "mini")
        .await
        .expect("leaderboard")
        .1
}

/// A hub with one submission (two answers wrong), scored at the current metric version, and
/// three human answers (see [`annotate`]); the submission's id.
async fn submitted_and_annotated() -> (TestServer, i64) {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let reply = submit_to(
        &server,
        "mini",
        "model=m",
        &token,
        answers(&records, &[1, 2]),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    assert_eq!(reply.json()["metric_version"], METRIC_VERSION);
    assert_eq!(reply.json()["outdated"], false);
    annotate(&server, &records, 3).await;
    (server, reply.id())
}

#[tokio::test]
async fn an_older_metric_version_is_marked_until_rescored_and_rescoring_changes_no_byte() {
    let (server, id) = submitted_and_annotated().await;

    // Verdicts were stored when the answers were finished, at the current version.
    let human_before = human_verdicts(&server.pool).await;
    assert_eq!(human_before.len(), 3);
    for (_, exact, _, task, _, version) in &human_before {
        assert_eq!(*version, Some(i64::from(METRIC_VERSION)));
        assert!(exact.is_some() && task.is_some());
    }
    assert_eq!(
        human_before.iter().filter(|v| v.3 == Some(true)).count(),
        2,
        "the reversed answer is wrong"
    );
    let scores_before = scores_text(&server.pool, id).await;
    let verdicts_before = verdict_rows(&server.pool, id).await;
    let board_before = board(&server.pool).await;
    assert!(board_before.iter().all(|r| !r.metric.outdated));

    // As a migration that raises the metric version would leave them: computed with version 1.
    age(&server.pool, id).await;
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE annotations SET metric_version = 1 WHERE item = \
             (SELECT min(item) FROM annotations)"
        )
    )
    .expect("age a human verdict");

    let marked = board(&server.pool).await;
    assert_eq!(marked.len(), 2);
    for row in &marked {
        assert!(row.metric.outdated, "{:?} must be marked", row.source);
        assert_eq!(row.metric.metric_version, 1);
    }
    let (status, json) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(status, 200);
    assert_eq!(json["metric_version"], METRIC_VERSION);
    for row in json["rows"].as_array().expect("rows") {
        assert_eq!(row["metric_version"], 1, "{row}");
        assert_eq!(row["outdated"], true, "{row}");
    }
    let page = server
        .get("/leaderboard/mini")
        .await
        .text()
        .await
        .expect("page");
    assert_eq!(
        page.matches("class=\"tag outdated\" title=").count(),
        2,
        "{page}"
    );
    assert!(page.contains("computed with metric version 1"), "{page}");

    let seen = Mutex::new(Vec::new());
    let summary = rescore::rescore(
        &Hub::from(server.pool.clone()),
        &operator(),
        Some("mini"),
        &|p| seen.lock().expect("lock").push(p),
    )
    .await
    .expect("rescored");
    assert_eq!(summary.metric_version, METRIC_VERSION);
    assert_eq!((summary.submissions, summary.submissions_changed), (1, 0));
    assert_eq!(
        (summary.human_answers, summary.human_answers_changed),
        (1, 0)
    );
    assert!(summary.failures.is_empty(), "{:?}", summary.failures);
    let seen = seen.into_inner().expect("lock");
    assert!(seen.contains(&RescoreProgress {
        dataset: "mini".to_owned(),
        stage: RescoreStage::Submissions,
        done: 1,
        total: 1,
    }));
    assert!(
        seen.iter()
            .any(|p| p.stage == RescoreStage::HumanAnswers && p.done == 1)
    );

    // Brought to the current version, bit for bit what was stored before.
    assert_eq!(scores_text(&server.pool, id).await, scores_before);
    assert_eq!(verdict_rows(&server.pool, id).await, verdicts_before);
    assert_eq!(human_verdicts(&server.pool).await, human_before);
    let rescored = board(&server.pool).await;
    assert_eq!(rescored, board_before);
    // The server's board, built before, is dropped as after an import by another process.
    let mut current = false;
    for _ in 0..100 {
        let (_, json) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
        let rows = json["rows"].as_array().expect("rows").clone();
        if rows.iter().all(|r| r["outdated"] == false) {
            current = true;
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    assert!(current, "the server still serves the outdated board");

    let audit = db!(
        server.pool,
        fetch_all,
        sqlx::query_as::<_, (String, String, Option<String>, String)>(
            "SELECT actor, target, dataset, detail FROM audit_log \
             WHERE action = 'metric.rescore'"
        )
    )
    .expect("audit");
    assert_eq!(audit.len(), 1);
    let (actor, target, dataset, detail) = &audit[0];
    assert_eq!(
        (actor.as_str(), target.as_str(), dataset.as_deref()),
        ("tester", "dataset mini", Some("mini"))
    );
    assert!(
        detail.contains(&format!("to metric version {METRIC_VERSION}"))
            && detail.contains("1 submissions (0 changed), 1 human answers (0 changed)"),
        "{detail}"
    );

    // Everything is current: a second run finds nothing to do (and says so in its own entry).
    let again = rescore::rescore(&Hub::from(server.pool.clone()), &operator(), None, &|_| {})
        .await
        .expect("rescored");
    assert_eq!((again.submissions, again.human_answers), (0, 0));
    assert_eq!(
        count(
            &server.pool,
            "SELECT count(*) FROM audit_log WHERE action = 'metric.rescore'"
        )
        .await,
        2
    );
}

/// Every number in a stored scores document moved (integers by one, fractions by a half): a
/// document of the same shape that no scoring of these answers produces.
fn tampered(scores: &str) -> String {
    fn nudge(value: &mut Value) {
        match value {
            Value::Number(n) => {
                *value = match n.as_u64() {
                    Some(n) => Value::from(n + 1),
                    None => Value::from(n.as_f64().expect("number") + 0.5),
                }
            }
            Value::Array(items) => items.iter_mut().for_each(nudge),
            Value::Object(fields) => fields.values_mut().for_each(nudge),
            _ => {}
        }
    }
    let mut value: Value = serde_json::from_str(scores).expect("scores are JSON");
    nudge(&mut value);
    let text = value.to_string();
    assert_ne!(text, scores, "the scores hold no number to tamper with");
    text
}

#[tokio::test]
async fn rescoring_rewrites_stored_results_the_current_metric_disagrees_with_and_counts_them() {
    let (server, id) = submitted_and_annotated().await;
    let scores_before = scores_text(&server.pool, id).await;
    let verdicts_before = verdict_rows(&server.pool, id).await;
    let human_before = human_verdicts(&server.pool).await;

    // As an older metric that judged differently would have left them: the stored scores, every
    // item's verdict and one human verdict are not what the current metric computes.
    scored_differently_before(&server.pool, id, &scores_before).await;
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE submission_items SET exact_match = NOT exact_match, \
             task_accuracy = NOT task_accuracy WHERE submission = $1"
        )
        .bind(id)
    )
    .expect("tamper the item verdicts");
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE annotations SET metric_version = 1, exact_match = NOT exact_match, \
             task_accuracy = NOT task_accuracy WHERE item = (SELECT min(item) FROM annotations)"
        )
    )
    .expect("tamper a human verdict");
    assert_ne!(verdict_rows(&server.pool, id).await, verdicts_before);
    assert_ne!(human_verdicts(&server.pool).await, human_before);

    let summary = rescore::rescore(
        &Hub::from(server.pool.clone()),
        &operator(),
        Some("mini"),
        &|_| {},
    )
    .await
    .expect("rescored");
    assert_eq!((summary.submissions, summary.submissions_changed), (1, 1));
    assert_eq!(
        (summary.human_answers, summary.human_answers_changed),
        (1, 1)
    );
    assert!(summary.failures.is_empty(), "{:?}", summary.failures);

    // What the current metric computes, byte for byte: what was stored on submission.
    assert_eq!(scores_text(&server.pool, id).await, scores_before);
    assert_eq!(verdict_rows(&server.pool, id).await, verdicts_before);
    assert_eq!(human_verdicts(&server.pool).await, human_before);
    let detail = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar::<_, String>(
            "SELECT detail FROM audit_log WHERE action = 'metric.rescore'"
        )
    )
    .expect("audit");
    assert!(
        detail.contains("1 submissions (1 changed), 1 human answers (1 changed), 0 failed"),
        "{detail}"
    );
}

#[tokio::test]
async fn answers_without_a_stored_verdict_are_judged_on_the_fly_until_rescored() {
    let (server, records) = spawn_app_with_release().await;
    annotate(&server, &records, 4).await;
    let stored = board(&server.pool).await;
    let human = stored
        .iter()
        .find(|r| r.source == RowSource::Human)
        .expect("the Human row");
    assert_eq!(human.overall.task_accuracy, Some(0.75));
    assert_eq!(human.human.expect("coverage").answers, 4);
    let verdicts = human_verdicts(&server.pool).await;

    // A database migrated from before verdicts were stored: answers without one.
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE annotations SET exact_match = NULL, semantic_match = NULL, \
             task_accuracy = NULL, pairwise_accuracy = NULL, metric_version = NULL"
        )
    )
    .expect("forget the verdicts");
    assert_eq!(
        board(&server.pool).await,
        stored,
        "judged now, the same row"
    );

    let summary = rescore::rescore(&Hub::from(server.pool.clone()), &operator(), None, &|_| {})
        .await
        .expect("rescored");
    assert_eq!(summary.human_answers, 4);
    assert_eq!(human_verdicts(&server.pool).await, verdicts);
    assert_eq!(board(&server.pool).await, stored);
}

/// A job context as the job mechanism hands one over: a payload, a stop flag, and the
/// progress values it stored.
struct FakeJob {
    payload: Value,
    stop: bool,
    progress: Mutex<Vec<Value>>,
}

impl RescoreJob for FakeJob {
    fn payload(&self) -> &Value {
        &self.payload
    }

    fn stop_requested(&self) -> bool {
        self.stop
    }

    async fn progress(&self, _hub: &Hub, progress: &RescoreJobProgress) -> Result<(), AppError> {
        let stored = serde_json::to_value(progress).expect("serialised");
        self.progress.lock().expect("lock").push(stored);
        Ok(())
    }
}

#[tokio::test]
async fn the_rescore_job_stops_when_asked_and_resumes_from_the_top() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    age(
        &server.pool,
        submit_to(&server, "mini", "model=m", &token, answers(&records, &[0]))
            .await
            .id(),
    )
    .await;
    let hub = Hub::from(server.pool.clone());
    let admin = Actor::Annotator("root".to_owned());
    let payload = RescorePayload::new(Some("mini"), &admin).to_json();

    // The summary the job stored last, after working it until asked to stop (at once or never).
    let work = async |stop: bool| {
        let job = FakeJob {
            payload: payload.clone(),
            stop,
            progress: Mutex::default(),
        };
        rescore::work_on(&hub, &job).await.expect("worked");
        let last = job.progress.lock().expect("lock").pop();
        last.expect("a summary")
    };
    let last = work(true).await;
    assert_eq!(last["stopped"], true);
    assert_eq!(last["submissions"], 0);
    assert!(board(&server.pool).await[0].metric.outdated);

    let last = work(false).await;
    assert_eq!(last["stopped"], false);
    assert_eq!(last["submissions"], 1);
    assert!(!board(&server.pool).await[0].metric.outdated);
    let actors = db!(
        server.pool,
        fetch_all,
        sqlx::query_scalar::<_, String>(
            "SELECT actor_kind || ' ' || actor FROM audit_log WHERE action = 'metric.rescore' \
             ORDER BY id"
        )
    )
    .expect("audit");
    assert_eq!(actors, vec!["annotator root", "annotator root"]);

    let unreadable = FakeJob {
        payload: serde_json::json!({"dataset": 7}),
        stop: false,
        progress: Mutex::default(),
    };
    let Err(AppError::Internal(e)) = rescore::work_on(&hub, &unreadable).await else {
        panic!("an unreadable payload must fail the job");
    };
    assert!(format!("{e:#}").contains("payload"), "{e:#}");
}

#[tokio::test]
async fn reimported_signatures_judge_the_human_answers_again_in_the_import() {
    // Under CI the fixtures must be here (the one rule of `fixtures::must_not_skip`).
    let Some(parity) = crate::fixtures::parity_dir() else {
        return;
    };
    let reference = parity.join("reference/eval_analyze/detailed_eval");
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    import(&pool, &parity, &options("parity")).await;
    let items = db!(
        pool,
        fetch_all,
        sqlx::query_scalar::<_, String>("SELECT item_id FROM items ORDER BY id")
    )
    .expect("items");
    // Each item answered as one of ENACT's prediction sets answered it, with ENACT's own verdict
    // on that answer (its evaluator, signatures on) to hold the hub's to: the semantically
    // equivalent orders where that set has one, else in turn the truth, two adjacent steps
    // swapped and a random order.
    let enact: Vec<std::collections::HashMap<String, Value>> =
        ["semequiv", "perfect", "adjswap", "random"]
            .iter()
            .map(|set| {
                let path = reference.join(format!("enact_ordering_{set}.jsonl"));
                std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
                    .lines()
                    .map(|line| serde_json::from_str::<Value>(line).expect("ENACT's row"))
                    .map(|row| (row["id"].as_str().expect("id").to_owned(), row))
                    .collect()
            })
            .collect();
    let mut chosen = Vec::new();
    for (i, id) in items.iter().enumerate() {
        let row = enact[0]
            .get(id)
            .or_else(|| enact[1 + i % 3].get(id))
            .or_else(|| enact[1].get(id))
            .unwrap_or_else(|| panic!("ENACT judged no answer for {id}"));
        let mut answer: Vec<u64> = row["model_answer"]
            .as_array()
            .map(|labels| labels.iter().filter_map(Value::as_u64).collect())
            .unwrap_or_default();
        let truth: Vec<u64> = row["ground_truth"]
            .as_array()
            .expect("ground truth")
            .iter()
            .map(|l| l.as_u64().expect("label"))
            .collect();
        answer.sort_unstable();
        let mut sorted_truth = truth.clone();
        sorted_truth.sort_unstable();
        if answer != sorted_truth {
            continue; // not an order of the steps: a person cannot give it
        }
        chosen.push((id.clone(), row.clone()));
    }
    let wrong = chosen
        .iter()
        .filter(|(_, row)| row["eval_metrics"]["exact_match"] == false)
        .count();
    let equivalent = chosen
        .iter()
        .filter(|(_, r)| {
            r["eval_metrics"]["exact_match"] == false && r["eval_metrics"]["semantic_match"] == true
        })
        .count();
    assert!(
        wrong >= 20 && equivalent >= 10 && chosen.len() >= 80,
        "{} answers, {wrong} wrong, {equivalent} equivalent orders",
        chosen.len()
    );

    let ann = crate::annotate::annotator_on(&pool, "ann", false).await;
    let ids: Vec<&str> = chosen.iter().map(|(id, _)| id.as_str()).collect();
    crate::annotate::assign_on(&pool, "parity", ann, &ids).await;
    let hub = Hub::from(pool.clone());
    let session = Session {
        annotator: ann,
        name: "ann".to_owned(),
        is_admin: false,
        csrf_token: String::new(),
    };
    for (id, row) in &chosen {
        let draft = Draft {
            slots: row["model_answer"]
                .as_array()
                .expect("answer")
                .iter()
                .map(|l| Some(l.as_u64().expect("label") as u8))
                .collect(),
            counts: InteractionCounts::default(),
            history: Vec::new(),
        };
        app::annotation::answer(&hub, &session, "parity", id, &draft)
            .await
            .expect("answered");
    }
    let exact_only = human_verdicts(&pool).await;

    let mut with_graphs = options("parity");
    with_graphs.scene_graphs = Some(parity.join("replayed_activities"));
    let report = import(&pool, &parity, &with_graphs).await;
    assert_eq!(report.signatures_updated, 96);
    let rejudged = human_verdicts(&pool).await;
    assert_eq!(rejudged.len(), chosen.len());
    assert!(
        rejudged
            .iter()
            .all(|v| v.5 == Some(i64::from(METRIC_VERSION)))
    );
    assert_ne!(rejudged, exact_only, "scene graphs give pairwise accuracy");

    // What the import stored is ENACT's verdict on each answer, metric by metric.
    let stored = db!(
        pool,
        fetch_all,
        sqlx::query_as::<
            _,
            (
                String,
                Option<bool>,
                Option<bool>,
                Option<bool>,
                Option<f64>
            ),
        >(
            "SELECT i.item_id, a.exact_match, a.semantic_match, a.task_accuracy, \
             a.pairwise_accuracy FROM annotations a JOIN items i ON i.id = a.item \
             WHERE a.outcome = 'answered'"
        )
    )
    .expect("stored verdicts");
    assert_eq!(stored.len(), chosen.len());
    let by_id: std::collections::HashMap<&str, &Value> =
        chosen.iter().map(|(id, row)| (id.as_str(), row)).collect();
    for (id, exact, semantic, task, pairwise) in &stored {
        let metrics = &by_id[id.as_str()]["eval_metrics"];
        let want = (
            metrics["exact_match"].as_bool(),
            metrics["semantic_match"].as_bool(),
            metrics["task_accuracy"].as_bool(),
        );
        assert_eq!((*exact, *semantic, *task), want, "{id}: {metrics}");
        let want_pairwise = metrics["pairwise_accuracy"].as_f64().expect("pairwise");
        let pairwise = pairwise.unwrap_or_else(|| panic!("{id}: no pairwise accuracy"));
        assert!(
            (pairwise - want_pairwise).abs() < 1e-9,
            "{id}: pairwise {pairwise}, ENACT {want_pairwise}"
        );
    }
}

#[tokio::test]
async fn an_admin_queues_a_rescore_that_a_job_worker_carries_out() {
    let (server, records) = spawn_app_with_release().await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let id = submit_to(
        &server,
        "mini",
        "model=m",
        &submitter,
        answers(&records, &[0]),
    )
    .await
    .id();
    age(&server.pool, id).await;

    let call = |token: &str, body: serde_json::Value| {
        server
            .call(reqwest::Method::POST, "/api/v1/admin/rescore")
            .bearer(token)
            .json(&body)
    };
    call(&submitter, serde_json::json!({})).expect(403).await;
    let unknown = call(&admin, serde_json::json!({"dataset": "nope"}))
        .expect(404)
        .await;
    assert!(unknown.error().contains("nope"), "{}", unknown.text);
    call(&admin, serde_json::json!({"dataset": "mini", "colour": 1}))
        .expect(422)
        .await;
    // Found by schemathesis: serde's derive also reads a struct from an array of its fields,
    // so `[]` queued a rescore of every dataset. The body is an object.
    let array = call(&admin, serde_json::json!([])).expect(422).await;
    assert!(array.error().contains("expected a map"), "{}", array.text);
    let queued = call(&admin, serde_json::json!({"dataset": "mini"}))
        .expect(202)
        .await
        .json();
    assert_eq!(queued["metric_version"], METRIC_VERSION);
    let job = JobId(queued["job"].as_i64().expect("a job id"));

    let hub = Hub::from(server.pool.clone());
    let worker = Worker::spawn(
        hub.clone(),
        app::job_handlers(),
        JobSettings {
            poll: std::time::Duration::from_millis(20),
            ..JobSettings::default()
        },
    );
    let mut row = None;
    for _ in 0..500 {
        let job = jobs::get(&hub, job).await.expect("read").expect("the job");
        if job.state == JobState::Done {
            row = Some(job);
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
    }
    worker.stop().await;
    let row = row.expect("the rescore job finished");
    let progress: Value =
        serde_json::from_str(row.progress.as_deref().unwrap_or("null")).expect("progress JSON");
    assert_eq!(progress["submissions"], 1, "{progress}");
    assert!(!board(&server.pool).await[0].metric.outdated);
    assert_eq!(
        count(
            &server.pool,
            "SELECT count(*) FROM audit_log WHERE action = 'metric.rescore' AND actor = 'root'"
        )
        .await,
        1
    );
}

#[tokio::test]
async fn the_command_line_rescores_in_the_foreground() {
    let (server, records) = spawn_app_with_release().await;
    if !on_sqlite() {
        return; // the command opens the database by path; the PostgreSQL run covers the rest
    }
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    age(
        &server.pool,
        submit_to(&server, "mini", "model=m", &token, answers(&records, &[0]))
            .await
            .id(),
    )
    .await;
    let run = |dataset: &str| {
        enact_hub()
            .args(["rescore", "--dataset", dataset, "--json", "--db"])
            .arg(server.db_path())
            .env("ENACT_HUB_OPERATOR", "ops")
            .output()
            .expect("run")
    };
    let out = run("mini");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).expect("JSON summary");
    assert_eq!(summary["submissions"], 1);
    assert_eq!(summary["metric_version"], METRIC_VERSION);
    assert!(!board(&server.pool).await[0].metric.outdated);
    let out = run("nope");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("nope"), "{stderr}");
}

/// Submission `id` as an older metric that scored it differently would have left it: its
/// stored scores tampered (see [`tampered`]) and its version 1.
async fn scored_differently_before(pool: &Pool, id: i64, scores: &str) {
    db!(
        pool,
        execute,
        sqlx::query("UPDATE submissions SET metric_version = 1, scores = $1 WHERE id = $2")
            .bind(tampered(scores))
            .bind(id)
    )
    .expect("tamper the scores");
}

/// One submission the current metric scores differently and one it cannot rescore (a stored
/// answer cut short, so its line is refused): both forms of a rescore count one changed and
/// one failed, naming the failed one; the command line exits non-zero.
#[tokio::test]
async fn a_rescore_counts_the_submissions_it_changed_and_failed_and_the_command_fails() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let changed = submit_to(&server, "mini", "model=a", &token, answers(&records, &[1])).await;
    let failing = submit_to(&server, "mini", "model=b", &token, answers(&records, &[])).await;
    let (changed, failing) = (changed.id(), failing.id());
    let scores = scores_text(&server.pool, changed).await;
    scored_differently_before(&server.pool, changed, &scores).await;
    age(&server.pool, failing).await;
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE submission_items SET raw_answer = '[2, 1' WHERE submission = $1 \
             AND item = (SELECT min(item) FROM submission_items WHERE submission = $1)"
        )
        .bind(failing)
    )
    .expect("cut a stored answer short");
    let counted = |summary: &Value| {
        let failures = summary["failures"].as_array().expect("failures");
        assert_eq!(failures.len(), 1, "{summary}");
        let failure = failures[0].as_str().expect("a reason");
        assert!(
            failure.contains(&format!("submission {failing}:")) && failure.contains("refused"),
            "{failure}"
        );
        assert_eq!(
            (&summary["submissions"], &summary["submissions_changed"]),
            (&Value::from(1), &Value::from(1)),
            "{summary}"
        );
    };

    let out = enact_hub()
        .args(["rescore", "--dataset", "mini", "--json", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "not rescored: dataset 'mini': submission {failing}:"
        )),
        "{stderr}"
    );
    counted(&serde_json::from_slice(&out.stdout).expect("a JSON summary"));
    assert_eq!(scores_text(&server.pool, changed).await, scores);

    // The job form, over the same two: the failed one is still below the current version.
    scored_differently_before(&server.pool, changed, &scores).await;
    let job = FakeJob {
        payload: RescorePayload::new(Some("mini"), &operator()).to_json(),
        stop: false,
        progress: Mutex::default(),
    };
    rescore::work_on(&Hub::from(server.pool.clone()), &job)
        .await
        .expect("worked");
    counted(&job.progress.lock().expect("lock").pop().expect("a summary"));
    assert_eq!(scores_text(&server.pool, changed).await, scores);
    let details = db!(
        server.pool,
        fetch_all,
        sqlx::query_scalar::<_, String>(
            "SELECT detail FROM audit_log WHERE action = 'metric.rescore' ORDER BY id"
        )
    )
    .expect("audit");
    assert_eq!(details.len(), 2);
    for detail in details {
        assert!(
            detail.contains("1 submissions (1 changed), 0 human answers (0 changed), 1 failed"),
            "{detail}"
        );
    }
}
