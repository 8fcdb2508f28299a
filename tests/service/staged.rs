//! Staged imports: batches written where no reader sees them, one cut-over, resume after an
//! interruption, abandon, and a failed import removing what it staged.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use enact_hub::app::Hub;
use enact_hub::app::import::{
    ImportError, ImportObserver, ImportOptions, ImportProgress, abandon, import_release,
};
use enact_hub::store::Pool;
use serde_json::Value;

use crate::helpers::{
    count, dataset_digest, db, fresh_db, import, options, tester, with_changed_questions,
    write_balanced_release, write_qa_file,
};

/// Options writing `batch` lines per transaction, replacing changed items.
fn batched(dataset: &str, batch: usize) -> ImportOptions {
    ImportOptions {
        replace: true,
        batch_lines: batch,
        ..options(dataset)
    }
}

/// `options` with an observer that panics once `batches` batches are committed: the import
/// stops there as a killed process would (its committed batches stay).
fn interrupted_after(mut options: ImportOptions, batches: usize) -> ImportOptions {
    let seen = Arc::new(AtomicUsize::new(0));
    options.progress = Some(ImportObserver(Arc::new(move |p: &ImportProgress| {
        // The first report comes before any batch (where the import starts).
        if !p.finished && seen.fetch_add(1, Ordering::SeqCst) == batches {
            panic!("interrupted after {batches} batches");
        }
    })));
    options
}

/// A 40-item release in `dir/changed` whose first images are frames no other release of these
/// tests has, so that importing it stages new frames; returns its folder.
fn release_with_new_frames(dir: &Path) -> std::path::PathBuf {
    let changed = dir.join("changed");
    let records = write_balanced_release(&changed, &[3], 40);
    let lines: Vec<String> = records
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if let Some(first) = r["images"][0].as_str() {
                let png = crate::helpers::png_bytes(9000 + i as u32, i);
                std::fs::write(changed.join(first), png).expect("image");
            }
            r.to_string()
        })
        .collect();
    write_qa_file(&changed, &lines);
    changed
}

/// Runs an import that the observer interrupts; it must not finish.
async fn run_interrupted(pool: &Pool, root: &Path, options: ImportOptions) {
    let hub = Hub::from(pool.clone());
    let root = root.to_path_buf();
    let outcome =
        tokio::spawn(async move { import_release(&hub, &tester(), &root, &options).await }).await;
    assert!(
        outcome
            .as_ref()
            .is_err_and(tokio::task::JoinError::is_panic),
        "the import was not interrupted: {:?}",
        outcome.map(|r| r.map(|r| r.summary_line()))
    );
}

/// Version B of a release: every question with another last line.
fn changed_version(root: &Path, records: &[Value]) {
    write_qa_file(root, &with_changed_questions(records));
}

/// Items of `dataset` with the new version's question.
async fn new_version_items(pool: &Pool, dataset: &str) -> (i64, i64) {
    let rows: Vec<(String,)> = db!(
        pool,
        fetch_all,
        sqlx::query_as(
            "SELECT i.question FROM items i JOIN datasets d ON d.id = i.dataset_id \
             WHERE d.name = $1"
        )
        .bind(dataset)
    )
    .expect("items");
    let new = rows.iter().filter(|(q,)| !q.contains("Now please")).count();
    (rows.len() as i64, new as i64)
}

/// What the app layer lists: the names of the datasets readers see.
async fn listed(pool: &Pool) -> Vec<String> {
    let mut conn = pool.acquire().await.expect("connection");
    enact_hub::store::datasets::overview(&mut conn)
        .await
        .expect("overview")
        .into_iter()
        .map(|d| d.dataset.name)
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_interrupted_import_is_invisible_and_resumes_after_its_last_batch() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3, 5], 30);
    let items = records.len() as i64;
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("main")).await;
    changed_version(&root, &records);

    // A first-time import into another dataset, interrupted: nothing of it is listed.
    run_interrupted(&pool, &root, interrupted_after(batched("other", 10), 3)).await;
    assert_eq!(listed(&pool).await, vec!["main".to_owned()]);
    let hub = Hub::from(pool.clone());
    assert!(
        enact_hub::app::datasets::overview(&hub)
            .await
            .map(|o| o.len() == 1)
            .unwrap_or(false),
        "the app layer lists only the published dataset"
    );

    // A replacing import, interrupted after 4 batches of 10: the dataset is wholly the old
    // version while 40 changed items wait in the staging version.
    run_interrupted(&pool, &root, interrupted_after(batched("main", 10), 4)).await;
    assert_eq!(new_version_items(&pool, "main").await, (items, 0));
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 2);
    // 40 and 30 records, unless a batch held the lock over 100 ms and the next ones shrank.
    let staged_row = "SELECT rows_done FROM staged_imports WHERE dataset = ";
    let staged = count(&pool, &format!("{staged_row}'main'")).await;
    let staged_other = count(&pool, &format!("{staged_row}'other'")).await;
    assert!((4..=40).contains(&staged) && (3..=30).contains(&staged_other));
    assert_eq!(
        count(&pool, "SELECT count(*) FROM items").await,
        items + staged + staged_other,
        "staged items wait beside the dataset's"
    );

    // Run again: it resumes after those records, writes only the other items, and lands.
    let report = import(&pool, &root, &batched("main", 10)).await;
    assert_eq!(
        report.resumed_rows as i64,
        staged,
        "{}",
        report.summary_line()
    );
    assert_eq!(report.items_written as i64, items - staged);
    assert_eq!(report.replaced_items as i64, items);
    assert_eq!(report.rows as i64, items);
    assert!(
        report
            .summary_line()
            .contains(&format!("resumed after {staged} records"))
    );
    assert_eq!(new_version_items(&pool, "main").await, (items, items));
    let resumed = dataset_digest(&pool, "main").await;

    // The same as an uninterrupted import of both versions into a fresh database.
    let other = tempfile::tempdir().expect("tempdir");
    let fresh = fresh_db(&other).await;
    let first = other.path().join("release");
    let again = write_balanced_release(&first, &[3, 5], 30);
    import(&fresh, &first, &options("main")).await;
    changed_version(&first, &again);
    let whole = import(&fresh, &first, &batched("main", 10)).await;
    assert_eq!((whole.resumed_rows, whole.items_written as i64), (0, items));
    assert_eq!(resumed, dataset_digest(&fresh, "main").await);
    assert_eq!(
        report.frames, whole.frames,
        "the resumed import counts the frames of the batches it skipped"
    );

    // The other dataset's unfinished import resumes too.
    let other_report = import(&pool, &root, &batched("other", 10)).await;
    assert_eq!(other_report.resumed_rows as i64, staged_other);
    assert_eq!(other_report.new_items as i64, items);
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);
    assert_eq!(
        listed(&pool).await,
        vec!["main".to_owned(), "other".to_owned()]
    );
    assert_eq!(count(&pool, "SELECT count(*) FROM datasets").await, 2);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_unfinished_import_is_abandoned_or_discarded_for_another_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3], 40);
    let items = records.len() as i64;
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    import(&pool, &root, &options("main")).await;
    let before = dataset_digest(&pool, "main").await;
    let frames = count(&pool, "SELECT count(*) FROM frames").await;

    // A new version whose images are new frames too: interrupted, then abandoned.
    let changed = release_with_new_frames(dir.path());
    run_interrupted(&pool, &changed, interrupted_after(batched("main", 8), 2)).await;
    assert!(count(&pool, "SELECT count(*) FROM frames").await > frames);
    let gone = abandon(&hub, &tester(), "main")
        .await
        .expect("abandon")
        .expect("there was an unfinished import");
    assert!((2..=16).contains(&gone.rows_done), "{}", gone.rows_done);
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);
    assert_eq!(count(&pool, "SELECT count(*) FROM items").await, items);
    assert_eq!(
        count(&pool, "SELECT count(*) FROM frames").await,
        frames,
        "the frames it staged went with it"
    );
    assert_eq!(dataset_digest(&pool, "main").await, before);
    assert!(
        abandon(&hub, &tester(), "main")
            .await
            .expect("abandon")
            .is_none()
    );

    // Interrupted again, then another file is imported: the stale staged version is discarded
    // and the other file imported from its start.
    run_interrupted(&pool, &changed, interrupted_after(batched("main", 8), 2)).await;
    changed_version(&root, &records);
    let report = import(&pool, &root, &batched("main", 8)).await;
    assert!(report.discarded_staged, "{}", report.summary_line());
    assert_eq!(report.resumed_rows, 0);
    assert_eq!(new_version_items(&pool, "main").await, (items, items));
    assert_eq!(count(&pool, "SELECT count(*) FROM frames").await, frames);
}

#[tokio::test]
async fn a_failed_import_removes_the_batches_it_staged() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3, 5], 25);
    let mut lines: Vec<String> = records.iter().map(Value::to_string).collect();
    lines.push("not json".to_owned());
    write_qa_file(&root, &lines);
    let pool = fresh_db(&dir).await;
    let err = import_release(
        &Hub::from(pool.clone()),
        &tester(),
        &root,
        &batched("d", 10),
    )
    .await
    .expect_err("the last line is not JSON");
    assert!(matches!(err, ImportError::Invalid { .. }), "{err}");
    for table in [
        "items",
        "item_images",
        "frames",
        "datasets",
        "staged_imports",
    ] {
        assert_eq!(
            count(&pool, &format!("SELECT count(*) FROM {table}")).await,
            0,
            "{table} after a refused import that had staged 10 batches"
        );
    }
}

/// `doctor`'s findings on imports and jobs: an unfinished import is a notice, one untouched for
/// a day a warning naming the command that removes it; a job whose instance died is a warning;
/// `--remove-stale` discards the stale import, audited; integrity passes on a sound file.
#[tokio::test]
async fn doctor_lists_stale_imports_and_dead_jobs_and_removes_what_it_is_told() {
    use enact_hub::app::doctor::{Level, Options, examine};

    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    write_balanced_release(&root, &[3], 40);
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let levels = |findings: &[enact_hub::app::doctor::Finding], check: &str| -> Vec<Level> {
        findings
            .iter()
            .filter(|f| f.check == check)
            .map(|f| f.level)
            .collect()
    };

    let healthy = examine(&hub, &tester(), Options::default())
        .await
        .expect("doctor");
    assert_eq!(healthy.worst(), Level::Ok, "{:#?}", healthy.findings);

    run_interrupted(&pool, &root, interrupted_after(batched("fresh", 8), 2)).await;
    let running = examine(&hub, &tester(), Options::default())
        .await
        .expect("doctor");
    assert_eq!(levels(&running.findings, "imports"), [Level::Notice]);
    assert_eq!(running.worst(), Level::Notice);

    // A day later, and a job whose instance stopped holding it.
    db!(
        pool,
        execute,
        sqlx::query("UPDATE staged_imports SET updated_at = '2000-01-01T00:00:00Z'")
    )
    .expect("age the import");
    db!(
        pool,
        execute,
        sqlx::query(
            "INSERT INTO jobs (kind, payload, state, attempts, lease_owner, lease_until_ms, \
             created_by) VALUES ('rescore', '{}', 'running', 1, 'host-1', 1000, 'tests')"
        )
    )
    .expect("a dead job");
    let stale = examine(&hub, &tester(), Options::default())
        .await
        .expect("doctor");
    assert_eq!(stale.worst(), Level::Warning);
    let import = stale
        .findings
        .iter()
        .find(|f| f.check == "imports")
        .expect("the import");
    assert_eq!(import.level, Level::Warning);
    assert!(import.detail.contains("'fresh'"), "{}", import.detail);
    assert!(
        import
            .fix
            .as_deref()
            .is_some_and(|fix| fix.contains("import --abandon fresh")),
        "{import:?}"
    );
    let job = stale
        .findings
        .iter()
        .find(|f| f.check == "jobs")
        .expect("the job");
    assert_eq!(job.level, Level::Warning);
    assert!(job.detail.contains("host-1"), "{}", job.detail);

    let removed = examine(
        &hub,
        &tester(),
        Options {
            remove_stale_imports: true,
            integrity: true,
            truncate_log: true,
        },
    )
    .await
    .expect("doctor");
    assert_eq!(levels(&removed.findings, "imports"), [Level::Notice]);
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);
    assert_eq!(
        count(
            &pool,
            "SELECT count(*) FROM audit_log WHERE detail LIKE 'abandoned the unfinished import%'"
        )
        .await,
        1
    );
    let integrity = levels(&removed.findings, "integrity");
    assert!(
        integrity == [Level::Ok] || (integrity == [Level::Notice] && pool.sqlite().is_none()),
        "{:#?}",
        removed.findings
    );
}

/// What a discard killed between its steps leaves (the staged import forgotten, part of its
/// rows deleted) is never resumed: the next run of the same file discards the rest and imports
/// from the start, so the dataset becomes the whole new version, not the rows that were left.
#[tokio::test]
async fn a_discard_cut_short_is_never_resumed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("release");
    let records = write_balanced_release(&root, &[3], 40);
    let items = records.len() as i64;
    let pool = fresh_db(&dir).await;
    import(&pool, &root, &options("main")).await;
    changed_version(&root, &records);
    run_interrupted(&pool, &root, interrupted_after(batched("main", 8), 2)).await;

    let mut conn = crate::helpers::write_tx(&pool).await;
    let staged = enact_hub::store::staged::for_dataset(&mut conn, "main")
        .await
        .expect("read")
        .expect("a staged import");
    enact_hub::store::staged::forget(&mut conn, staged.id)
        .await
        .expect("forget");
    let deleted = enact_hub::store::staged::delete_items(&mut conn, staged.staging, 3)
        .await
        .expect("delete some");
    assert_eq!(deleted, 3);
    conn.commit().await.expect("commit");

    let report = import(&pool, &root, &batched("main", 8)).await;
    assert!(report.discarded_staged, "{}", report.summary_line());
    assert_eq!(report.resumed_rows, 0);
    assert_eq!(new_version_items(&pool, "main").await, (items, items));
    assert_eq!(count(&pool, "SELECT count(*) FROM staged_imports").await, 0);
}

#[tokio::test]
async fn discarding_a_staged_import_keeps_the_frames_of_episodes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let root = dir.path().join("release");
    write_balanced_release(&root, &[3], 4);
    import(&pool, &root, &options("main")).await;
    // An episode's frames and thumbnails are linked to no item.
    let shots = dir.path().join("shots");
    std::fs::create_dir_all(&shots).expect("dir");
    for n in 0..3u32 {
        let png = crate::helpers::png_bytes(7000 + n, n as usize);
        std::fs::write(shots.join(format!("shot_{n}.png")), png).expect("frame");
    }
    enact_hub::app::episodes::import(&hub, &tester(), &shots, "kitchen", "")
        .await
        .expect("episode imported");
    let frames = count(&pool, "SELECT count(*) FROM frames").await;

    // A new version with new frames, interrupted, then abandoned: what it staged goes, the
    // episode's frames stay.
    let changed = release_with_new_frames(dir.path());
    run_interrupted(&pool, &changed, interrupted_after(batched("main", 8), 2)).await;
    assert!(count(&pool, "SELECT count(*) FROM frames").await > frames);
    abandon(&hub, &tester(), "main")
        .await
        .expect("abandon")
        .expect("there was an unfinished import");
    assert_eq!(count(&pool, "SELECT count(*) FROM frames").await, frames);
    let linked = "SELECT count(*) FROM episode_frames e JOIN frames f ON f.id = e.frame \
                  JOIN frames t ON t.id = e.thumbnail";
    assert_eq!(count(&pool, linked).await, 3);
}
