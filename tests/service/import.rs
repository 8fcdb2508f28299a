//! The importer: validation of every invalid-row class, all-or-nothing writes, re-imports.

use enact_hub::app::import::{ImportError, import_release};
use enact_hub::store;
use enact_hub::store::Pool;
use serde_json::{Value, json};

use crate::helpers::*;

async fn item_count(pool: &Pool) -> i64 {
    count(pool, "SELECT count(*) FROM items").await
}

async fn frame_count(pool: &Pool) -> i64 {
    count(pool, "SELECT count(*) FROM frames").await
}

/// Writes a release of two valid items plus `bad` (built from a third valid record) and returns
/// the problems the importer reports, all on line 3; asserts nothing was written.
async fn problems_for(
    bad: impl FnOnce(&mut serde_json::Map<String, Value>, &std::path::Path) -> Option<String>,
) -> Vec<String> {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let a = write_record(&root, "task_1", true, 3, 1);
    let b = write_record(&root, "task_1", false, 4, 2);
    let mut c = write_record(&root, "task_1", true, 5, 3)
        .as_object()
        .cloned()
        .expect("object");
    let raw = bad(&mut c, &root).unwrap_or_else(|| Value::Object(c).to_string());
    write_qa_file(&root, &[a.to_string(), b.to_string(), raw]);
    let pool = fresh_db(&dir).await;
    let err = import_release(&pool.clone().into(), &tester(), &root, &options("d"))
        .await
        .expect_err("the bad row must be rejected");
    let ImportError::Invalid { lines, rows, .. } = &err else {
        panic!("expected Invalid, got {err}");
    };
    assert_eq!(*rows, 3);
    assert_eq!(lines.len(), 1, "{:?}", err.details());
    assert_eq!(lines[0].line, 3);
    assert_eq!(item_count(&pool).await, 0, "nothing may be written");
    assert_eq!(frame_count(&pool).await, 0, "nothing may be written");
    err.details()
}

fn assert_mentions(problems: &[String], needles: &[&str]) {
    for needle in needles {
        assert!(
            problems.iter().any(|p| p.contains(needle)),
            "expected a problem mentioning {needle:?}, got {problems:#?}"
        );
    }
    assert!(
        problems.iter().all(|p| p.starts_with("line 3")),
        "{problems:#?}"
    );
}

#[tokio::test]
async fn valid_release_imports_with_counts_and_deduplicated_frames() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4, 10]);
    // A second item that shows the same key frames (same bytes) as the first one.
    let mut twin = records[0].clone();
    twin["id"] = json!("twin_item");
    write_qa_file(
        &root,
        &records
            .iter()
            .chain([&twin])
            .map(Value::to_string)
            .collect::<Vec<_>>(),
    );
    let pool = fresh_db(&dir).await;
    let report = import(&pool, &root, &options("mini")).await;
    assert_eq!(report.new_items, 7);
    assert_eq!(report.frames, 3 + 3 + 4 + 4 + 10 + 10);
    assert_eq!(report.new_frames, report.frames);
    assert_eq!(item_count(&pool).await, 7);
    assert_eq!(frame_count(&pool).await, 34);
    let mut conn = pool.acquire().await.expect("conn");
    let d = store::datasets::by_name(&mut conn, "mini")
        .await
        .expect("query")
        .expect("dataset");
    let item = store::items::get(&mut conn, d.id, "twin_item")
        .await
        .expect("query")
        .expect("item");
    assert_eq!(item.actions.len(), 2);
    assert_eq!(item.images.len(), 3);
    assert_eq!(item.gt_answer, vec![2, 1]);
    assert_eq!(item.images[1].label(), "Next State 1");
}

#[tokio::test]
async fn reimporting_the_same_file_changes_nothing_and_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3, 6]);
    let pool = fresh_db(&dir).await;
    let first = import(&pool, &root, &options("mini")).await;
    assert!(first.changed_anything());
    let second = import(&pool, &root, &options("mini")).await;
    assert!(!second.changed_anything());
    assert_eq!(second.unchanged_items, 4);
    assert_eq!(second.new_frames, 0);
    assert!(
        second.summary_line().starts_with("nothing changed"),
        "{}",
        second.summary_line()
    );
    assert_eq!(item_count(&pool).await, 4);
}

#[tokio::test]
async fn changed_item_is_a_conflict_unless_replace() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;

    records[1]["gt_answer"] = json!([1, 2]);
    write_qa_file(
        &root,
        &records.iter().map(Value::to_string).collect::<Vec<_>>(),
    );
    let err = import_release(&pool.clone().into(), &tester(), &root, &options("mini"))
        .await
        .expect_err("conflict");
    assert!(matches!(err, ImportError::Conflict { .. }), "{err}");
    assert!(
        err.details()[0].starts_with("line 2"),
        "{:?}",
        err.details()
    );

    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&pool, &root, &replace).await;
    assert_eq!(report.replaced_items, 1);
    assert_eq!(report.unchanged_items, 3);
    let id = records[1]["id"].as_str().expect("id");
    let gt: String = db!(
        pool,
        fetch_one,
        sqlx::query_scalar("SELECT gt_answer FROM items WHERE item_id = $1").bind(id)
    )
    .expect("gt");
    assert_eq!(gt, "[1,2]");
}

#[tokio::test]
async fn bad_json_is_rejected_with_its_line() {
    let p = problems_for(|_, _| Some("{\"id\": \"x\", ".to_owned())).await;
    assert_mentions(&p, &["invalid JSON"]);
}

#[tokio::test]
async fn missing_fields_are_rejected_by_name() {
    let p = problems_for(|r, _| {
        r.remove("question");
        r.remove("key_frame_ids");
        None
    })
    .await;
    assert_mentions(&p, &["`question`: missing", "`key_frame_ids`: missing"]);
}

#[tokio::test]
async fn step_length_outside_3_to_10_is_rejected() {
    let p = problems_for(|r, _| {
        r.insert(
            "type".into(),
            json!("forward_world_modeling_ordering_2_steps"),
        );
        None
    })
    .await;
    assert_mentions(&p, &["`type`: step length 2 is outside 3..10"]);
}

#[tokio::test]
async fn ground_truth_that_is_not_a_permutation_is_rejected() {
    let p = problems_for(|r, _| {
        r.insert("gt_answer".into(), json!([1, 2, 2, 4]));
        None
    })
    .await;
    assert_mentions(
        &p,
        &["`gt_answer`: [1, 2, 2, 4] is not a permutation of 1..4"],
    );
}

#[tokio::test]
async fn image_count_other_than_l_is_rejected() {
    let p = problems_for(|r, _| {
        let images = r["images"].as_array().expect("images")[..4].to_vec();
        r.insert("images".into(), Value::Array(images));
        None
    })
    .await;
    assert_mentions(&p, &["`images`: has 4 images, the type says L = 5"]);
}

#[tokio::test]
async fn missing_image_file_is_rejected_with_its_index() {
    let p = problems_for(|r, root| {
        let path = r["images"][2].as_str().expect("path").to_owned();
        std::fs::remove_file(root.join(path)).expect("remove");
        None
    })
    .await;
    assert_mentions(&p, &["`images[2]`: image file not found"]);
}

#[tokio::test]
async fn undecodable_image_is_rejected() {
    let p = problems_for(|r, root| {
        let path = r["images"][0].as_str().expect("path").to_owned();
        std::fs::write(root.join(path), b"definitely not a png").expect("overwrite");
        None
    })
    .await;
    assert_mentions(&p, &["`images[0]`: not a decodable image"]);
}

#[tokio::test]
async fn image_path_leaving_the_release_is_rejected() {
    let p = problems_for(|r, _| {
        r["images"][1] = json!("../outside.png");
        None
    })
    .await;
    assert_mentions(
        &p,
        &["`images[1]`", "relative path inside the release folder"],
    );
}

#[tokio::test]
async fn question_without_one_line_per_action_is_rejected() {
    let p = problems_for(|r, _| {
        let q = r["question"]
            .as_str()
            .expect("question")
            .replace("[Action 3] ", "");
        r.insert("question".into(), json!(q));
        None
    })
    .await;
    assert_mentions(
        &p,
        &["`question`: expected 4 lines [Action 1]..[Action 4], found 3"],
    );
}

#[tokio::test]
async fn duplicate_ids_are_rejected_on_the_later_line() {
    let p = problems_for(|r, _| {
        r.insert(
            "id".into(),
            json!("task_1_forward_world_modeling_ordering_3_steps_00000001"),
        );
        None
    })
    .await;
    assert_mentions(&p, &["duplicate id", "first seen on line 1"]);
}

#[tokio::test]
async fn skip_invalid_imports_the_valid_rows_and_lists_the_rest() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let good = write_record(&root, "t", true, 3, 1);
    let mut bad = write_record(&root, "t", false, 3, 2);
    bad["gt_answer"] = json!([3, 1]);
    write_qa_file(
        &root,
        &[good.to_string(), "not json".to_owned(), bad.to_string()],
    );
    let pool = fresh_db(&dir).await;
    let mut opts = options("d");
    opts.skip_invalid = true;
    let report = import(&pool, &root, &opts).await;
    assert_eq!(report.new_items, 1);
    let lines: Vec<usize> = report.skipped.iter().map(|s| s.line).collect();
    assert_eq!(lines, vec![2, 3]);
    assert_eq!(item_count(&pool).await, 1);
}

#[tokio::test]
async fn a_jsonl_path_resolves_images_against_the_parent_of_qa() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3]);
    let file = root.join("QA").join("enact_ordering.jsonl");
    let pool = fresh_db(&dir).await;
    let report = import(&pool, &file, &options("d")).await;
    assert_eq!(report.new_items, 2);
}

#[tokio::test]
async fn enact_sample_imports_16_items_and_rejects_rows_without_images() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let sample = fixtures.join("enact-sample");
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;

    let report = import(&pool, &sample, &options("sample")).await;
    assert_eq!(report.new_items, 16);
    let again = import(&pool, &sample, &options("sample")).await;
    assert!(!again.changed_anything());
    assert_eq!(item_count(&pool).await, 16);

    let no_images = sample.join("QA").join("enact_ordering_320_no_images.jsonl");
    let fresh_dir = tempfile::tempdir().expect("tempdir");
    let fresh = fresh_db(&fresh_dir).await;
    let err = import_release(
        &fresh.clone().into(),
        &tester(),
        &no_images,
        &options("sample"),
    )
    .await
    .expect_err("rows without images");
    let ImportError::Invalid { lines, rows, .. } = &err else {
        panic!("expected Invalid, got {err}");
    };
    assert_eq!(*rows, 320);
    assert_eq!(lines.len(), 304);
    assert!(lines.iter().all(|l| {
        l.problems
            .iter()
            .all(|p| p.message.starts_with("image file not found"))
    }));
    assert_eq!(item_count(&fresh).await, 0);

    let mut skip = options("sample");
    skip.skip_invalid = true;
    for _ in 0..2 {
        let report = import(&fresh, &no_images, &skip).await;
        assert_eq!(report.skipped.len(), 304);
        assert_eq!(report.new_items + report.unchanged_items, 16);
        assert_eq!(item_count(&fresh).await, 16);
    }
}

#[tokio::test]
async fn inverse_items_without_scene_graphs_get_action_text_signatures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    let report = import(&pool, &root, &options("mini")).await;
    assert_eq!(report.scene_graph_items, 0);
    assert_eq!(report.action_text_items, 2, "{}", report.summary_line());
    assert_eq!(report.exact_only_items, 2);
    let sources: Vec<String> = db!(
        pool,
        fetch_all,
        sqlx::query_scalar("SELECT source FROM item_signatures ORDER BY item")
    )
    .expect("sources");
    assert_eq!(sources, vec!["action_text", "action_text"]);
}

#[tokio::test]
async fn scene_graph_import_stores_enacts_transition_signatures_and_upgrades_on_reimport() {
    let Some(fixtures) = fixtures_dir() else {
        return;
    };
    let parity = fixtures.join("enact-parity");
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    // First without scene graphs: forward items are exact-only.
    let plain = import(&pool, &parity, &options("parity")).await;
    assert_eq!(plain.exact_only_items, 48);
    let mut with_graphs = options("parity");
    with_graphs.scene_graphs = Some(parity.join("replayed_activities"));
    let report = import(&pool, &parity, &with_graphs).await;
    assert_eq!(report.new_items, 0);
    assert_eq!(report.signatures_updated, 96);
    assert_eq!(report.scene_graph_items, 96);
    let again = import(&pool, &parity, &with_graphs).await;
    assert!(!again.changed_anything(), "{}", again.summary_line());

    // The stored tables hold ENACT's visible and full sets of every chronological transition.
    let reference = std::fs::read_to_string(parity.join("reference/transition_signatures.jsonl"))
        .expect("reference");
    let mut conn = pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, "parity")
        .await
        .expect("q")
        .expect("dataset");
    let mut compared = 0;
    for line in reference.lines() {
        let r: Value = serde_json::from_str(line).expect("json");
        let id = r["id"].as_str().expect("id");
        let (source, json) = store::items::semantics_json(&mut conn, dataset.id, id)
            .await
            .expect("q")
            .expect("stored");
        assert_eq!(source.as_str(), "scene_graph");
        let table: enact_hub::core::verifier::ItemSignatures =
            serde_json::from_str(&json).expect("table");
        for (i, t) in r["transitions"]
            .as_array()
            .expect("transitions")
            .iter()
            .enumerate()
        {
            for (view, key) in [
                (enact_hub::core::scene_graph::View::Visible, "visible"),
                (enact_hub::core::scene_graph::View::Full, "full"),
            ] {
                let expected: std::collections::BTreeSet<String> = t[key]
                    .as_array()
                    .expect("set")
                    .iter()
                    .map(|s| s.as_str().expect("str").to_owned())
                    .collect();
                let ours: std::collections::BTreeSet<String> = table
                    .signature_set(view, i, i + 1)
                    .unwrap_or_else(|| panic!("{id} {i} {key}: not covered"))
                    .unwrap_or_else(|e| panic!("{id} {i} {key}: {e}"))
                    .into_iter()
                    .map(str::to_owned)
                    .collect();
                assert_eq!(ours, expected, "{id} transition {i} {key}");
                compared += 1;
            }
        }
    }
    assert_eq!(compared, 1056);
}

/// The importer works a batch of lines at a time; a file of several batches is still one
/// all-or-nothing import whose error lists the problems of every batch.
#[tokio::test]
async fn a_release_of_several_batches_is_still_all_or_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3], 300);
    let mut lines: Vec<String> = records.iter().map(Value::to_string).collect();
    lines.insert(1, "not json".to_owned());
    lines.push(records[0].to_string());
    write_qa_file(&root, &lines);
    let pool = fresh_db(&dir).await;
    let err = import_release(&pool.clone().into(), &tester(), &root, &options("big"))
        .await
        .expect_err("two bad lines, in the first and the second batch");
    let ImportError::Invalid {
        lines: bad, rows, ..
    } = &err
    else {
        panic!("expected Invalid, got {err}");
    };
    assert_eq!(*rows, 602);
    let at: Vec<usize> = bad.iter().map(|l| l.line).collect();
    assert_eq!(at, vec![2, 602], "{:?}", err.details());
    assert!(
        err.details()[1].contains("first seen on line 1"),
        "{:?}",
        err.details()
    );
    assert_eq!(
        item_count(&pool).await,
        0,
        "the first batch was rolled back"
    );
    assert_eq!(
        frame_count(&pool).await,
        0,
        "the first batch was rolled back"
    );

    let lines: Vec<String> = records.iter().map(Value::to_string).collect();
    write_qa_file(&root, &lines);
    let report = import(&pool, &root, &options("big")).await;
    assert_eq!((report.rows, report.new_items), (600, 600));
    assert_eq!(report.frames as i64, frame_count(&pool).await);
    assert_eq!(item_count(&pool).await, 600);
    let again = import(&pool, &root, &options("big")).await;
    assert_eq!((again.unchanged_items, again.new_items), (600, 0));
}

/// An import's write-ahead log is as large as its new frames; `enact-hub import` folds it into
/// the database and empties it before closing, even while other connections are open.
#[tokio::test]
async fn the_log_of_an_import_can_be_emptied_while_connections_are_open() {
    if !on_sqlite() {
        eprintln!("the write-ahead log file is SQLite's: skipped on PostgreSQL");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_release(&root, &[3, 10]);
    let pool = fresh_db(&dir).await;
    let hub: enact_hub::app::Hub = pool.clone().into();
    import(&pool, &root, &options("d")).await;
    let wal = dir.path().join("test.db-wal");
    let size = || {
        std::fs::metadata(&wal)
            .map(|m| m.len())
            .expect("the log exists")
    };
    assert!(size() > 0, "the import wrote to the log");
    // A second connection stays open, as a pool's do.
    let _other = pool.acquire().await.expect("connection");
    assert!(hub.truncate_log().await, "nothing else is reading");
    assert_eq!(size(), 0);
    assert_eq!(item_count(&pool).await, 4, "the items are in the database");
}

/// Stores a ground-truth submission of `model` to `dataset` through the use case.
async fn submit_truth(pool: &Pool, dataset: &str, model: &str, records: &[Value]) {
    use enact_hub::app::{Hub, submissions};
    use enact_hub::core::credentials::{Role, Scope};
    use enact_hub::core::submission::{Provenance, SubmissionMetadata};
    let (_, token) = api_token(pool, model, Role::Submitter, None, None).await;
    let hub = Hub::from(pool.clone());
    let caller = enact_hub::app::tokens::authorize(&hub, &token, Scope::Submit)
        .await
        .expect("caller");
    let metadata = SubmissionMetadata {
        model: model.to_owned(),
        ..SubmissionMetadata::default()
    };
    let body = ground_truth_answers(records).into_bytes();
    submissions::submit(
        &hub,
        &caller,
        dataset,
        metadata,
        Provenance::Submitted,
        None,
        async { Ok(body) },
    )
    .await
    .expect("stored");
}

#[tokio::test]
async fn a_replacing_import_sweeps_the_replaced_items_verdicts_after_its_cut_over() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    let items = item_count(&pool).await;
    submit_truth(&pool, "mini", "m1", &records).await;
    submit_truth(&pool, "mini", "m2", &records).await;
    let verdicts = "SELECT count(*) FROM submission_items";
    assert_eq!(count(&pool, verdicts).await, 2 * items);

    reverse_first(&root, &mut records, 2);
    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&pool, &root, &replace).await;
    assert_eq!(report.replaced_items, 2);
    // The cut-over left them; the sweep after it deleted exactly those: 2 items × 2 submissions.
    assert_eq!(report.swept_verdicts, 4);
    assert!(report.longest_transaction_ms >= report.longest_sweep_ms);
    assert_eq!(count(&pool, verdicts).await, 2 * (items - 2));
    assert_eq!(
        count(
            &pool,
            "SELECT count(*) FROM submission_items v WHERE NOT EXISTS \
             (SELECT 1 FROM items i WHERE i.id = v.item)"
        )
        .await,
        0
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM verdict_sweeps").await, 0);
}

#[tokio::test]
async fn verdicts_left_to_sweep_are_not_counted_and_a_restarted_sweep_supersedes_an_older_one() {
    use enact_hub::app::Hub;
    use enact_hub::app::import::sweep_replaced_verdicts;
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    submit_truth(&pool, "mini", "m1", &records).await;
    submit_truth(&pool, "mini", "m2", &records).await;
    let hub = Hub::from(pool.clone());
    let dataset: i64 = count(&pool, "SELECT id FROM datasets WHERE name = 'mini'").await;
    let exact = || async {
        let mut conn = pool.acquire().await.expect("conn");
        store::red_flags::exact_answers(&mut conn, dataset)
            .await
            .expect("exact answers")
            .iter()
            .map(|s| s.exact)
            .collect::<Vec<_>>()
    };
    let before = exact().await;
    assert_eq!(before, vec![records.len(); 2]);

    // As a process killed between a cut-over and its sweep leaves it: an item gone, its verdicts
    // not, and the sweep pending.
    let gone: i64 = count(&pool, "SELECT min(id) FROM items").await;
    db!(
        pool,
        execute,
        sqlx::query("DELETE FROM items WHERE id = $1").bind(gone)
    )
    .expect("delete");
    db!(
        pool,
        execute,
        sqlx::query("INSERT INTO verdict_sweeps (dataset) VALUES ($1)").bind(dataset)
    )
    .expect("sweep");
    let orphans = "SELECT count(*) FROM submission_items v WHERE NOT EXISTS \
                   (SELECT 1 FROM items i WHERE i.id = v.item)";
    assert_eq!(count(&pool, orphans).await, 2);
    assert_eq!(
        exact().await,
        vec![records.len() - 1; 2],
        "left verdicts are not counted"
    );

    // A sweeper of an older generation stops at its next step, writing nothing.
    let mut conn = write_tx(&pool).await;
    let pending = store::staged::verdict_sweeps(&mut conn)
        .await
        .expect("sweeps");
    assert_eq!(pending.len(), 1);
    let older = store::staged::VerdictSweep {
        generation: pending[0].generation - 1,
        ..pending[0]
    };
    assert_eq!(
        store::staged::sweep_submission(&mut conn, &older)
            .await
            .expect("step"),
        (0, false)
    );
    conn.commit().await.expect("commit");
    assert_eq!(count(&pool, orphans).await, 2);

    let swept = sweep_replaced_verdicts(&hub).await.expect("sweep");
    assert_eq!((swept.submissions, swept.verdicts), (2, 2));
    assert_eq!(count(&pool, orphans).await, 0);
    assert_eq!(count(&pool, "SELECT count(*) FROM verdict_sweeps").await, 0);
    assert_eq!(
        sweep_replaced_verdicts(&hub).await.expect("again"),
        Default::default()
    );
}

/// Every table with a foreign key to `referenced`, with the column, as the database lists them.
async fn references_to(pool: &Pool, referenced: &str) -> Vec<(String, String)> {
    let mut found: Vec<(String, String)> = match pool {
        Pool::Sqlite(p) => sqlx::query_as(
            "SELECT t.name, f.\"from\" FROM sqlite_master t, pragma_foreign_key_list(t.name) f \
             WHERE t.type = 'table' AND f.\"table\" = $1",
        )
        .bind(referenced)
        .fetch_all(p)
        .await
        .expect("sqlite foreign keys"),
        Pool::Pg(p) => sqlx::query_as(
            "SELECT k.table_name::text, k.column_name::text \
             FROM information_schema.referential_constraints r \
             JOIN information_schema.key_column_usage k ON k.constraint_name = r.constraint_name \
              AND k.constraint_schema = r.constraint_schema \
             JOIN information_schema.constraint_column_usage u \
              ON u.constraint_name = r.unique_constraint_name \
              AND u.constraint_schema = r.unique_constraint_schema \
             WHERE r.constraint_schema = current_schema() AND u.table_name = $1",
        )
        .bind(referenced)
        .fetch_all(p)
        .await
        .expect("postgres foreign keys"),
    };
    found.sort();
    found
}

#[tokio::test]
async fn a_swapping_cut_over_knows_every_table_that_names_a_dataset_or_an_item() {
    // A table a migration adds that names a dataset and is missing from the list would be
    // left on the retired row by a swapping cut-over and deleted with it; one that names an
    // item would keep what was made on a replaced item until its deletion.
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let mut datasets: Vec<(String, String)> = store::staged::DATASET_REFERENCES
        .iter()
        .map(|(table, column, _)| (table.to_string(), column.to_string()))
        .chain(
            [
                ("items", "dataset_id"),
                ("retired_datasets", "dataset"),
                ("staged_imports", "staging"),
            ]
            .map(|(t, c)| (t.to_owned(), c.to_owned())),
        )
        .collect();
    datasets.sort();
    assert_eq!(references_to(&pool, "datasets").await, datasets);
    let mut items: Vec<(String, String)> = store::staged::MADE_ON_ITEMS
        .iter()
        .map(|table| (table.to_string(), "item".to_owned()))
        .chain(["item_images", "item_signatures"].map(|t| (t.to_owned(), "item".to_owned())))
        .collect();
    items.sort();
    assert_eq!(references_to(&pool, "items").await, items);
}

/// Reverses the ground truth of `records[..n]` and writes the release again.
fn reverse_first(root: &std::path::Path, records: &mut [Value], n: usize) {
    for record in &mut records[..n] {
        let mut reversed = record["gt_answer"].as_array().expect("gt").clone();
        reversed.reverse();
        record["gt_answer"] = Value::Array(reversed);
    }
    write_qa_file(
        root,
        &records.iter().map(Value::to_string).collect::<Vec<_>>(),
    );
}

/// The row id of dataset `name`.
async fn dataset_row(pool: &Pool, name: &str) -> i64 {
    let mut conn = pool.acquire().await.expect("conn");
    store::datasets::by_name(&mut conn, name)
        .await
        .expect("query")
        .expect("the dataset")
        .id
}

/// Assigns `items` (row ids) to a new annotator named `name`.
async fn assign_to_new_annotator(pool: &Pool, name: &str, items: &[i64]) {
    let mut tx = write_tx(pool).await;
    let annotator = store::annotations::create_annotator(&mut tx, name, false, name)
        .await
        .expect("annotator");
    let pairs: Vec<(i64, i64)> = items.iter().map(|&item| (annotator, item)).collect();
    store::annotations::assign(&mut tx, &pairs)
        .await
        .expect("assign");
    tx.commit().await.expect("commit");
}

#[tokio::test]
async fn a_cut_over_replacing_most_of_a_dataset_retires_its_row_and_keeps_all_that_names_it() {
    use enact_hub::core::dataset::AnswerVisibility;
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    set_mini_answers(&pool, AnswerVisibility::Public).await;
    submit_truth(&pool, "mini", "m1", &records).await;
    submit_truth(&pool, "mini", "m2", &records).await;
    let before = dataset_row(&pool, "mini").await;
    let item_row = |dataset: i64, item: &Value| {
        let item = item["id"].as_str().expect("id");
        format!("SELECT id FROM items WHERE item_id = '{item}' AND dataset_id = {dataset}")
    };
    let kept = count(&pool, &item_row(before, &records[3])).await;
    let replaced = count(&pool, &item_row(before, &records[0])).await;
    assign_to_new_annotator(&pool, "ann", &[kept, replaced]).await;

    // Three of the four items replaced: moving them in would move more rows than moving the
    // kept one out, so the staged row takes the dataset's place.
    reverse_first(&root, &mut records, 3);
    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&pool, &root, &replace).await;
    assert_eq!((report.replaced_items, report.unchanged_items), (3, 1));
    let after = dataset_row(&pool, "mini").await;
    assert_ne!(after, before, "the staged row is the dataset now");
    assert_eq!(report.retired_items, 3, "{}", report.summary_line());
    assert_eq!(report.swept_verdicts, 2 * 3);
    assert!(report.longest_transaction_ms >= report.longest_sweep_ms);

    // Nothing of the old row is left, and everything that named the dataset names the new one.
    assert_eq!(count(&pool, "SELECT count(*) FROM datasets").await, 1);
    assert_eq!(
        count(&pool, "SELECT count(*) FROM retired_datasets").await,
        0
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);
    let on_new = |table: &str| format!("SELECT count(*) FROM {table} WHERE dataset = {after}");
    assert_eq!(count(&pool, &on_new("submissions")).await, 2);
    assert_eq!(count(&pool, &on_new("dataset_settings")).await, 1);
    assert_eq!(
        count(
            &pool,
            &format!("SELECT count(*) FROM items WHERE dataset_id = {after}")
        )
        .await,
        4
    );
    assert_eq!(
        count(&pool, &item_row(after, &records[3])).await,
        kept,
        "the kept item keeps its row"
    );
    // The kept item's verdicts and assignment stay; the replaced one's are gone.
    assert_eq!(
        count(&pool, "SELECT count(*) FROM submission_items").await,
        2
    );
    assert_eq!(
        count(&pool, "SELECT count(*) FROM assignments").await,
        1,
        "only the kept item's assignment is left"
    );
    assert_eq!(
        count(
            &pool,
            &format!("SELECT count(*) FROM assignments WHERE item = {kept}")
        )
        .await,
        1
    );
    assert_eq!(
        count(
            &pool,
            "SELECT count(*) FROM frames f WHERE NOT EXISTS \
             (SELECT 1 FROM item_images ii WHERE ii.frame = f.id)"
        )
        .await,
        0
    );
    let mut conn = pool.acquire().await.expect("conn");
    let overview = store::datasets::overview(&mut conn)
        .await
        .expect("overview");
    assert_eq!(
        overview
            .iter()
            .map(|d| (d.dataset.name.as_str(), d.items.total))
            .collect::<Vec<_>>(),
        vec![("mini", 4)]
    );
}

#[tokio::test]
async fn a_cut_over_replacing_a_few_items_moves_them_into_the_dataset_row() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_balanced_release(&root, &[3, 4], 3);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    submit_truth(&pool, "mini", "m1", &records).await;
    let before = dataset_row(&pool, "mini").await;

    reverse_first(&root, &mut records, 1);
    let mut replace = options("mini");
    replace.replace = true;
    let report = import(&pool, &root, &replace).await;
    assert_eq!((report.replaced_items, report.unchanged_items), (1, 11));
    assert_eq!(dataset_row(&pool, "mini").await, before, "the same row");
    assert_eq!((report.retired_items, report.swept_verdicts), (0, 1));
    assert_eq!(count(&pool, "SELECT count(*) FROM datasets").await, 1);
    assert_eq!(count(&pool, "SELECT count(*) FROM items").await, 12);
    assert_eq!(
        count(&pool, "SELECT count(*) FROM submission_items").await,
        11
    );
}

#[tokio::test]
async fn what_is_written_to_a_retired_row_after_its_cut_over_moves_to_the_dataset() {
    use enact_hub::app::Hub;
    use enact_hub::app::import::delete_retired_datasets;
    use enact_hub::core::dataset::AnswerVisibility;
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    set_mini_answers(&pool, AnswerVisibility::Public).await;
    submit_truth(&pool, "mini", "m1", &records).await;
    let mini = dataset_row(&pool, "mini").await;

    // As a cut-over leaves it when a submission and a settings change resolved the dataset
    // just before it and wrote just after: a retired row of mini's with an item, a submission
    // and a settings row of its own (mini has one too: mini's wins).
    let retired: i64 = db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, i64>(
            "INSERT INTO datasets (name) VALUES ('\u{2}retired mini') RETURNING id"
        )
    )
    .expect("retired row");
    for sql in [
        "INSERT INTO retired_datasets (dataset, name) VALUES ($1, 'mini')",
        "UPDATE submissions SET dataset = $1",
        "UPDATE items SET dataset_id = $1 WHERE id = (SELECT min(id) FROM items)",
        "INSERT INTO dataset_settings (dataset, answers) VALUES ($1, 'hidden')",
    ] {
        db!(pool, execute, sqlx::query(sql).bind(retired)).unwrap_or_else(|e| panic!("{sql}: {e}"));
    }
    assert_eq!(
        count(
            &pool,
            &format!("SELECT count(*) FROM items WHERE dataset_id = {mini}")
        )
        .await,
        3,
        "the retired row's item is not mini's"
    );

    let hub = Hub::from(pool.clone());
    let done = delete_retired_datasets(&hub).await.expect("delete");
    assert_eq!((done.datasets, done.items, done.repointed), (1, 1, 1));
    assert_eq!(count(&pool, "SELECT count(*) FROM datasets").await, 1);
    assert_eq!(
        count(
            &pool,
            &format!("SELECT count(*) FROM submissions WHERE dataset = {mini}")
        )
        .await,
        1,
        "the late submission is mini's"
    );
    assert_eq!(
        count(
            &pool,
            &format!("SELECT count(*) FROM dataset_settings WHERE dataset = {mini} AND answers = 'public'")
        )
        .await,
        1,
        "mini's own settings row wins"
    );
    assert_eq!(
        count(&pool, "SELECT count(*) FROM dataset_settings").await,
        1
    );
    assert_eq!(
        delete_retired_datasets(&hub).await.expect("again"),
        Default::default()
    );
}

#[tokio::test]
async fn a_submission_whose_dataset_is_replaced_while_its_body_arrives_is_scored_on_the_new_one() {
    use enact_hub::app::submissions::{self, Submitted};
    use enact_hub::app::{Hub, tokens};
    use enact_hub::core::credentials::{Role, Scope};
    use enact_hub::core::submission::{Provenance, SubmissionMetadata};
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let mut records = write_release(&root, &[3, 4]);
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("mini")).await;
    let before = dataset_row(&pool, "mini").await;
    let (_, token) = api_token(&pool, "m1", Role::Submitter, None, None).await;
    let hub = Hub::from(pool.clone());
    let caller = tokens::authorize(&hub, &token, Scope::Submit)
        .await
        .expect("caller");
    let body = ground_truth_answers(&records).into_bytes();
    // The dataset is looked up when the request starts; its body arrives after a replacing
    // import swapped the dataset's row (and deleted the old one).
    reverse_first(&root, &mut records, 3);
    let (import_pool, import_root) = (pool.clone(), root.clone());
    let arriving = async move {
        let mut replace = options("mini");
        replace.replace = true;
        let report = import(&import_pool, &import_root, &replace).await;
        assert_eq!(report.retired_items, 3);
        Ok(body)
    };
    let metadata = SubmissionMetadata {
        model: "m1".to_owned(),
        ..SubmissionMetadata::default()
    };
    let stored = submissions::submit(
        &hub,
        &caller,
        "mini",
        metadata,
        Provenance::Submitted,
        None,
        arriving,
    )
    .await
    .expect("stored");
    let Submitted::Created(row) = stored else {
        panic!("a new submission");
    };
    let after = dataset_row(&pool, "mini").await;
    assert_ne!(after, before);
    assert_eq!(row.dataset_id, after);
    assert_eq!(
        count(
            &pool,
            &format!(
                "SELECT count(*) FROM submission_items v JOIN items i ON i.id = v.item \
                 WHERE v.submission = {} AND i.dataset_id = {after}",
                row.id
            )
        )
        .await,
        4,
        "scored against the new version's four items"
    );
}
