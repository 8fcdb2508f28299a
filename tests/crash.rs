//! Crash safety: the server (and the import command) killed with SIGKILL at random moments,
//! again and again, while they write. After every kill the database must pass
//! `PRAGMA integrity_check` and `foreign_key_check`; every write acknowledged before the kill
//! (a 2xx reply, or an import that exited 0) must be there with the content it was
//! acknowledged with; nothing may be half-written (an import is all old or all new, a
//! submission has every item verdict, an audit entry exists exactly for what was done); and no
//! draft may outlive its finished item.
//!
//! The server-side jobs (a model run against a stand-in endpoint, a rescore, an import from the
//! import folder) are killed the same way while the restarted server's worker takes them over
//! after each dead lease (`serve --job-lease`, short here): the job finishes, nothing is stored
//! twice, and a run asks the endpoint again at most what was in flight at each kill. These
//! trials run on PostgreSQL too when `ENACT_HUB_TEST_POSTGRES` names a server (a fresh
//! database each, as the service suite makes them); the others use SQLite files only.
//!
//! `ENACT_CRASH_KILLS` sets the kills per kind (default 50), `ENACT_CRASH_JOB_KILLS` per job
//! (default 10); `ENACT_CRASH_SEED` the seed of the kill moments (default: random, printed so a
//! failure can be replayed).

#[path = "support/fixtures.rs"]
mod fixtures;
#[path = "service/helpers.rs"]
#[allow(unused_imports)]
mod helpers;
#[path = "support/standin.rs"]
mod standin;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use enact_hub::app::Hub;
use enact_hub::core::credentials::{Role, hash_password, random_token, token_hash};
use enact_hub::core::metric::METRIC_VERSION;
use enact_hub::store;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};
use sha2::{Digest, Sha256};
use sqlx::SqlitePool;
use tempfile::TempDir;

use helpers::{
    answers, dataset_digest, with_changed_questions, write_balanced_release, write_qa_file,
};

fn kills() -> usize {
    std::env::var("ENACT_CRASH_KILLS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(50)
}

/// A seeded generator for one kind; the seed is printed so a failing run can be replayed.
fn rng(kind: &str) -> ChaCha8Rng {
    let seed = std::env::var("ENACT_CRASH_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(rand::random::<u64>);
    eprintln!("crash {kind}: ENACT_CRASH_SEED={seed}");
    ChaCha8Rng::seed_from_u64(seed)
}

fn enact_hub() -> Command {
    Command::new(env!("CARGO_BIN_EXE_enact-hub"))
}

/// A free loopback port (bound, read and released).
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .expect("bind")
        .local_addr()
        .expect("addr")
        .port()
}

/// `enact-hub serve` on `db`, ready to answer.
struct Server {
    child: Child,
    base: String,
}

impl Server {
    async fn start(db: &Path) -> Server {
        Server::start_with(db, &[], None).await
    }

    /// `serve` on `db` with `extra` arguments, its log appended to `log` when given.
    async fn start_with(db: &Path, extra: &[String], log: Option<&Path>) -> Server {
        let port = free_port();
        let stderr = match log {
            Some(log) => Stdio::from(
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(log)
                    .expect("the server's log"),
            ),
            None => Stdio::null(),
        };
        let child = enact_hub()
            .args([
                "serve",
                "--daily-quota",
                "1000000",
                "--total-quota",
                "1000000",
            ])
            .args(extra)
            .arg("--db")
            .arg(db)
            .arg("--addr")
            .arg(format!("127.0.0.1:{port}"))
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .expect("spawn serve");
        let base = format!("http://127.0.0.1:{port}");
        let client = reqwest::Client::new();
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            if let Ok(r) = client.get(format!("{base}/healthz")).send().await
                && r.status().is_success()
            {
                break;
            }
            assert!(
                Instant::now() < deadline,
                "the server did not start on {db:?}"
            );
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
        Server { child, base }
    }

    /// What a failure's message should say of the process: whether it still runs, what its
    /// threads are doing, and whether it answers.
    async fn report(&self) -> String {
        let pid = self.child.id();
        let status = std::fs::read_to_string(format!("/proc/{pid}/status"))
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("State:"))
                    .map(str::to_owned)
            })
            .unwrap_or_else(|| "State: gone".to_owned());
        let mut threads = Vec::new();
        if let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) {
            for task in tasks.flatten() {
                let path = task.path();
                let read = |file: &str| {
                    std::fs::read_to_string(path.join(file))
                        .unwrap_or_default()
                        .trim()
                        .to_owned()
                };
                threads.push(format!("{} in {}", read("comm"), read("wchan")));
            }
        }
        threads.sort();
        let health = match reqwest::Client::new()
            .get(format!("{}/healthz", self.base))
            .timeout(Duration::from_secs(5))
            .send()
            .await
        {
            Ok(reply) => reply.status().to_string(),
            Err(e) => format!("no answer: {e}"),
        };
        format!(
            "pid {pid}: {status}; /healthz: {health}; threads: {}",
            threads.join(", ")
        )
    }

    /// SIGKILL, and wait until the process is gone.
    fn kill(mut self) {
        self.child.kill().expect("SIGKILL");
        self.child.wait().expect("reaped");
    }
}

/// The checks every kill is followed by, on the database file itself.
async fn check_database(pool: &SqlitePool, after: &str) {
    let integrity: String = sqlx::query_scalar("PRAGMA integrity_check")
        .fetch_one(pool)
        .await
        .expect("integrity_check");
    assert_eq!(integrity, "ok", "after {after}");
    let broken: Vec<(String,)> = sqlx::query_as("SELECT \"table\" FROM pragma_foreign_key_check")
        .fetch_all(pool)
        .await
        .expect("foreign_key_check");
    assert!(
        broken.is_empty(),
        "after {after}: dangling rows in {broken:?}"
    );
    let outlived: i64 = sqlx::query_scalar(
        "SELECT count(*) FROM drafts d JOIN annotations a \
         ON a.annotator = d.annotator AND a.item = d.item",
    )
    .fetch_one(pool)
    .await
    .expect("drafts");
    assert_eq!(
        outlived, 0,
        "after {after}: a draft outlived its finished item"
    );
}

async fn open(db: &Path) -> SqlitePool {
    store::open(db).await.expect("open the database")
}

/// A write transaction for the trial's own setup rows, in a write gate of its own (the store's
/// write functions take nothing else).
async fn write_tx(pool: &SqlitePool) -> store::Tx {
    let turn = store::gate::WriteGate::default()
        .enter(store::gate::Lane::Bulk)
        .await;
    store::Pool::Sqlite(pool.clone())
        .begin()
        .await
        .expect("a write transaction")
        .holding(turn)
}

/// A release of `per_cell` items per direction × L in 3, 5, 8.
fn release(dir: &Path, per_cell: u32) -> Vec<Value> {
    write_balanced_release(dir, &[3, 5, 8], per_cell)
}

/// Imports killed at random moments, alternating two versions of the same release into one
/// dataset with `--replace`: after each kill the dataset is wholly the old version or wholly
/// the new one, never a mix, and each import adds exactly one audit entry when it committed
/// (it exited successfully or its version is now there) and none when it is seen to have
/// changed nothing (killed before its commit, or after committing what was there already:
/// then one or none).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn imports_killed_at_random_are_all_or_nothing() {
    let mut rng = rng("imports");
    let dir = TempDir::new().expect("tempdir");
    let db = dir.path().join("crash.db");
    let a = dir.path().join("a");
    let records = release(&a, 12);
    // Version B: the same items, each question with another last line.
    let b = dir.path().join("b");
    std::fs::create_dir_all(&b).expect("dir");
    copy_dir(&a.join("QA"), &b.join("QA"));
    let changed = with_changed_questions(&records);
    write_qa_file(&b, &changed);
    let items = records.len() as i64;

    let import = |from: &Path| {
        enact_hub()
            .arg("import")
            .arg(from)
            .args(["--dataset", "main", "--replace", "--db"])
            .arg(&db)
            .env("ENACT_HUB_OPERATOR", "crash")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn import")
    };
    // How long a replacing import takes here (frames stored already), to spread the kills
    // over it.
    assert!(import(&a).wait().expect("import").success());
    let started = Instant::now();
    assert!(import(&b).wait().expect("import").success());
    let whole = started.elapsed();
    let mut current = 'b';
    let mut finished_imports = 2;
    let mut logged = import_entries(&db).await;
    assert_eq!(logged, 2, "the two imports that finished");
    let mut killed_before_landing = 0;
    for k in 0..kills() {
        let (version, from) = if k % 2 == 0 { ('a', &a) } else { ('b', &b) };
        let mut child = import(from);
        let at = whole.mul_f64(rng.random_range(0.0..1.3));
        tokio::time::sleep(at).await;
        let finished = matches!(child.try_wait(), Ok(Some(status)) if status.success());
        let _ = child.kill();
        let status = child.wait().expect("reaped");
        if finished || status.success() {
            current = version;
            finished_imports += 1;
        }
        let pool = open(&db).await;
        let after = format!("import kill {k} at {at:?}");
        check_database(&pool, &after).await;
        let (stored, new_version): (i64, i64) = sqlx::query_as(
            "SELECT count(*), coalesce(sum(question NOT LIKE '%Now please%'), 0) FROM items \
             WHERE dataset_id = (SELECT id FROM datasets WHERE name = 'main')",
        )
        .fetch_one(&pool)
        .await
        .expect("items");
        assert_eq!(stored, items, "{after}: the dataset lost items");
        // An import killed after its commit but before it exited counts as finished too.
        let seen = if new_version == items {
            'b'
        } else if new_version == 0 {
            'a'
        } else {
            panic!("{after}: {new_version} of {items} items are of the new version");
        };
        let landed = seen != current || finished || status.success();
        if seen != current {
            assert!(!finished, "{after}: a finished import is not there");
            current = seen;
            finished_imports += 1;
        }
        pool.close().await;
        // One entry for an import that committed, none for one killed before its commit; an
        // import of the version already there may have committed before its kill unseen.
        let now = import_entries(&db).await;
        if landed {
            assert_eq!(
                now,
                logged + 1,
                "{after}: an import that landed, {now} entries"
            );
        } else if seen != version {
            killed_before_landing += 1;
            assert_eq!(
                now, logged,
                "{after}: an import killed before its commit is logged"
            );
        } else {
            assert!(
                now == logged || now == logged + 1,
                "{after}: {} entries added by one import",
                now - logged
            );
        }
        logged = now;
    }
    eprintln!(
        "crash imports: {} kills, {finished_imports} imports landed, {killed_before_landing} \
         killed before landing",
        kills()
    );
    // The trial tried both ends of the window: imports that landed and (over enough kills
    // for one to fall early, about one in seven does) imports it cut short.
    assert!(
        finished_imports > 2 && (killed_before_landing > 0 || kills() < 20),
        "{finished_imports} imports landed, {killed_before_landing} were killed before landing"
    );
}

/// How many imports of dataset `main` the audit log holds.
async fn import_entries(db: &Path) -> i64 {
    let pool = open(db).await;
    let logged: i64 = sqlx::query_scalar(
        "SELECT count(*) FROM audit_log WHERE action = 'dataset.import' AND dataset = 'main'",
    )
    .fetch_one(&pool)
    .await
    .expect("audit");
    pool.close().await;
    logged
}

/// [`dataset_digest`] of dataset `main`.
async fn main_digest(pool: &SqlitePool) -> String {
    dataset_digest(&store::Pool::Sqlite(pool.clone()), "main").await
}

/// Imports of 600 items in batches of 20 lines killed at random moments, each run resuming the
/// one killed before it: after every kill the dataset is wholly the old version (or wholly
/// the new one, once an import has landed); a run that finishes wrote exactly the items no
/// earlier run had committed (its summary's `items_written` and `resumed_rows` against the
/// staged rows it found), and the dataset it leaves is identical, by content hash, to an
/// uninterrupted import's.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn killed_imports_resume_after_their_last_batch_to_the_uninterrupted_result() {
    const BATCH: &str = "20";
    let mut rng = rng("resumed imports");
    let dir = TempDir::new().expect("tempdir");
    let a = dir.path().join("a");
    let records = release(&a, 100);
    let items = records.len() as i64;
    let b = dir.path().join("b");
    std::fs::create_dir_all(&b).expect("dir");
    copy_dir(&a.join("QA"), &b.join("QA"));
    let changed = with_changed_questions(&records);
    write_qa_file(&b, &changed);
    let import = |db: &Path, from: &Path| {
        enact_hub()
            .arg("import")
            .arg(from)
            .args([
                "--dataset",
                "main",
                "--replace",
                "--json",
                "--batch-lines",
                BATCH,
            ])
            .arg("--db")
            .arg(db)
            .env("ENACT_HUB_OPERATOR", "crash")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn import")
    };
    let finish = |child: Child| -> Value {
        let out = child.wait_with_output().expect("import");
        assert!(out.status.success(), "the import failed");
        serde_json::from_slice(&out.stdout).expect("the report as JSON")
    };

    // The uninterrupted imports: A, then B over it, each version's content hash.
    let reference = dir.path().join("reference.db");
    finish(import(&reference, &a));
    let pool = open(&reference).await;
    let digest_a = main_digest(&pool).await;
    pool.close().await;
    let started = Instant::now();
    let whole_b = finish(import(&reference, &b));
    let whole = started.elapsed();
    assert_eq!(whole_b["items_written"], items);
    let pool = open(&reference).await;
    let digest_b = main_digest(&pool).await;
    pool.close().await;

    let db = dir.path().join("crash.db");
    finish(import(&db, &a));
    let mut current = ('a', &digest_a);
    let mut next = ('b', &b, &digest_b);
    let (mut kills_done, mut landed, mut resumed) = (0, 0, 0);
    // When to kill: between the latest kill that came before any batch was committed and the
    // earliest that came after the import landed. The batches are a short stretch of the
    // uninterrupted import's time, and one timing of it can be off (a cold page cache, a busy
    // machine): kills at fixed shares of it once missed the stretch 50 times running.
    let (initial_early, initial_late) = (whole.mul_f64(0.1), whole.mul_f64(0.75));
    let (mut early, mut late) = (initial_early, initial_late);
    while kills_done < kills().max(30) {
        // Kill it up to three times, then let it run to the end.
        for _ in 0..3 {
            let mut child = import(&db, next.1);
            // Mostly while it writes its batches (it starts with the process and the file's
            // hash; a resumed run has less to write).
            if late <= early + Duration::from_millis(5) {
                (early, late) = (initial_early, initial_late);
            }
            let at = early + (late - early).mul_f64(rng.random_range(0.0..1.0));
            tokio::time::sleep(at).await;
            let _ = child.kill();
            let status = child.wait().expect("reaped");
            kills_done += 1;
            let after = format!("resumed import kill {kills_done} at {at:?}");
            let pool = open(&db).await;
            check_database(&pool, &after).await;
            let digest = main_digest(&pool).await;
            let committed: i64 =
                sqlx::query_scalar("SELECT coalesce(max(rows_done), 0) FROM staged_imports")
                    .fetch_one(&pool)
                    .await
                    .expect("staged");
            pool.close().await;
            if status.success() || digest == *next.2 {
                late = late.min(at);
            } else if committed == 0 {
                early = early.max(at);
            }
            if status.success() {
                // It landed before the kill.
                assert_eq!(&digest, next.2, "{after}: landed, but not whole");
                current = (next.0, next.2);
                break;
            }
            assert!(
                digest == *current.1 || digest == *next.2,
                "{after}: the dataset is neither version whole"
            );
            if digest == *next.2 {
                // Killed after its cut-over committed, before it exited.
                current = (next.0, next.2);
                break;
            }
        }
        if current.0 != next.0 {
            // What earlier runs committed, which this run must not write again.
            let pool = open(&db).await;
            let (staged_rows, staged_items): (i64, i64) = sqlx::query_as(
                "SELECT coalesce(max(s.rows_done), 0), \
                 (SELECT count(*) FROM items i JOIN staged_imports t ON t.staging = i.dataset_id) \
                 FROM staged_imports s",
            )
            .fetch_one(&pool)
            .await
            .expect("staged");
            pool.close().await;
            let report = finish(import(&db, next.1));
            assert_eq!(report["resumed_rows"], staged_rows, "{report}");
            assert_eq!(
                report["items_written"].as_i64(),
                Some(items - staged_items),
                "the committed batches were written again: {report}"
            );
            assert_eq!(report["replaced_items"], items);
            if staged_rows > 0 {
                resumed += 1;
            }
            let pool = open(&db).await;
            check_database(&pool, "a finished resumed import").await;
            assert_eq!(
                &main_digest(&pool).await,
                next.2,
                "the resumed import differs from the uninterrupted one"
            );
            let staged: i64 = sqlx::query_scalar("SELECT count(*) FROM staged_imports")
                .fetch_one(&pool)
                .await
                .expect("staged");
            assert_eq!(staged, 0);
            pool.close().await;
            current = (next.0, next.2);
        }
        landed += 1;
        next = if current.0 == 'a' {
            ('b', &b, &digest_b)
        } else {
            ('a', &a, &digest_a)
        };
    }
    eprintln!(
        "resumed imports: {kills_done} kills, {landed} imports landed, {resumed} of them \
         resumed after committed batches"
    );
    assert!(resumed > 0, "no import was killed after a committed batch");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for entry in std::fs::read_dir(from).expect("read_dir") {
        let entry = entry.expect("entry");
        let target = to.join(entry.file_name());
        if entry.file_type().expect("type").is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).expect("copy");
        }
    }
}

/// A database with the release imported as dataset "mini".
async fn seeded(dir: &TempDir, per_cell: u32) -> (PathBuf, Vec<Value>) {
    let db = dir.path().join("crash.db");
    let root = dir.path().join("release");
    let records = release(&root, per_cell);
    let out = enact_hub()
        .arg("import")
        .arg(&root)
        .args(["--dataset", "mini", "--db"])
        .arg(&db)
        .output()
        .expect("import");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (db, records)
}

/// Submissions posted one after another while the server is killed at a random moment; after
/// each restart every acknowledged submission reads back as it was acknowledged.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submissions_acknowledged_before_a_kill_survive_it() {
    let mut rng = rng("submissions");
    let dir = TempDir::new().expect("tempdir");
    let (db, records) = seeded(&dir, 4).await;
    let items = records.len() as i64;
    let token = {
        let out = enact_hub()
            .args([
                "token",
                "create",
                "--name",
                "team",
                "--role",
                "submitter",
                "--db",
            ])
            .arg(&db)
            .output()
            .expect("token");
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .last()
            .expect("token line")
            .trim()
            .to_owned()
    };
    let client = reqwest::Client::new();
    // id -> (model, body hash, the JSON the 201 carried)
    let mut acknowledged: BTreeMap<i64, (String, String, Value)> = BTreeMap::new();
    let mut sent = 0;
    let mut rounds_acknowledged = 0;
    for k in 0..kills() {
        let server = Server::start(&db).await;
        // What the last round acknowledged reads back the same through the restarted server.
        for (id, (_, _, reply)) in acknowledged.range(..).rev().take(3) {
            let now: Value = client
                .get(format!("{}/api/v1/submissions/{id}", server.base))
                .bearer_auth(&token)
                .send()
                .await
                .expect("read")
                .json()
                .await
                .expect("json");
            for field in ["id", "model", "scores", "created_at", "dataset"] {
                assert_eq!(now[field], reply[field], "submission {id}: {field} changed");
            }
        }
        let writer = {
            let (client, base, token, records) = (
                client.clone(),
                server.base.clone(),
                token.clone(),
                records.clone(),
            );
            let first = sent;
            tokio::spawn(async move {
                let mut done = Vec::new();
                for n in first.. {
                    let body = answers(&records, &[n % records.len()]);
                    let model = format!("m{n}");
                    let reply = client
                        .post(format!(
                            "{base}/api/v1/datasets/mini/submissions?model={model}"
                        ))
                        .bearer_auth(&token)
                        .body(body.clone())
                        .send()
                        .await;
                    // A refused connection or a cut reply is the kill; any other status is not.
                    let Ok(reply) = reply else { break };
                    assert_eq!(reply.status(), 201, "submission {model} refused");
                    let Ok(json) = reply.json::<Value>().await else {
                        break;
                    };
                    let hash = hex::encode(Sha256::digest(body.as_bytes()));
                    done.push((json["id"].as_i64().expect("id"), model, hash, json));
                }
                done
            })
        };
        let at = Duration::from_millis(rng.random_range(5..400));
        tokio::time::sleep(at).await;
        server.kill();
        let done = writer.await.expect("writer");
        rounds_acknowledged += usize::from(!done.is_empty());
        sent += done.len() + 1;
        for (id, model, hash, json) in done {
            acknowledged.insert(id, (model, hash, json));
        }

        let pool = open(&db).await;
        let after = format!("submission kill {k} at {at:?}");
        check_database(&pool, &after).await;
        let stored: BTreeMap<i64, (String, String)> = sqlx::query_as::<_, (i64, String, String)>(
            "SELECT id, model, body_sha256 FROM submissions",
        )
        .fetch_all(&pool)
        .await
        .expect("submissions")
        .into_iter()
        .map(|(id, model, hash)| (id, (model, hash)))
        .collect();
        for (id, (model, hash, _)) in &acknowledged {
            assert_eq!(
                stored.get(id),
                Some(&(model.clone(), hash.clone())),
                "{after}: acknowledged submission {id} is lost or changed"
            );
        }
        let partial: i64 = sqlx::query_scalar(
            "SELECT count(*) FROM submissions s WHERE \
             (SELECT count(*) FROM submission_items i WHERE i.submission = s.id) != ?",
        )
        .bind(items)
        .fetch_one(&pool)
        .await
        .expect("items");
        assert_eq!(partial, 0, "{after}: a submission without all its verdicts");
        let logged: BTreeSet<String> =
            sqlx::query_scalar("SELECT target FROM audit_log WHERE action = 'submission.create'")
                .fetch_all(&pool)
                .await
                .expect("audit")
                .into_iter()
                .collect();
        let expected: BTreeSet<String> =
            stored.keys().map(|id| format!("submission {id}")).collect();
        assert_eq!(
            logged, expected,
            "{after}: audit entries and submissions differ"
        );
        pool.close().await;
    }
    eprintln!(
        "crash submissions: {} kills, {} submissions acknowledged and found, {rounds_acknowledged} \
         rounds acknowledged some",
        kills(),
        acknowledged.len()
    );
    // The survival checks above held something: kills fell after acknowledged submissions.
    assert!(
        rounds_acknowledged > 0 && !acknowledged.is_empty(),
        "no submission was acknowledged before any kill: nothing was checked"
    );
}

/// One annotator saving drafts and finishing items while the server is killed at a random
/// moment; after each restart every acknowledged answer is stored as acknowledged, and the
/// stored draft of an unfinished item is the last acknowledged save or one sent after it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn annotation_saves_and_answers_acknowledged_before_a_kill_survive_it() {
    let mut rng = rng("annotations");
    let dir = TempDir::new().expect("tempdir");
    let (db, records) = seeded(&dir, 60).await;
    let gt: BTreeMap<String, Vec<u64>> = records
        .iter()
        .map(|r| {
            let gt = r["gt_answer"].as_array().expect("gt");
            (
                r["id"].as_str().expect("id").to_owned(),
                gt.iter().map(|v| v.as_u64().expect("label")).collect(),
            )
        })
        .collect();
    // The annotator, their queue and a login link, set up before the first start.
    let link = {
        let pool = open(&db).await;
        let mut tx = write_tx(&pool).await;
        let annotator = store::annotations::create_annotator(
            &mut tx,
            "ann",
            false,
            &token_hash(&random_token()),
        )
        .await
        .expect("insert");
        tx.commit().await.expect("commit");
        let mut conn = pool.acquire().await.expect("conn");
        sqlx::query("UPDATE annotators SET password_hash = ?, invite_hash = NULL WHERE id = ?")
            .bind(hash_password("a long enough password").expect("hash"))
            .bind(annotator)
            .execute(&mut *conn)
            .await
            .expect("password");
        let dataset = store::datasets::by_name(&mut conn, "mini")
            .await
            .expect("query")
            .expect("dataset");
        let ids: Vec<String> = gt.keys().cloned().collect();
        let rows = store::annotations::item_rowids(&mut conn, dataset.id, &ids)
            .await
            .expect("query")
            .into_iter()
            .collect::<Option<Vec<i64>>>()
            .expect("known");
        drop(conn);
        let pairs: Vec<(i64, i64)> = rows.into_iter().map(|r| (annotator, r)).collect();
        let mut tx = write_tx(&pool).await;
        store::annotations::assign(&mut tx, &pairs)
            .await
            .expect("assign");
        tx.commit().await.expect("commit");
        let link = enact_hub::app::annotators::login_link(&Hub::from(pool.clone()), annotator)
            .await
            .expect("link");
        pool.close().await;
        link
    };
    let client = reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .expect("client");
    let (cookie, csrf) = {
        let server = Server::start(&db).await;
        let r = client
            .get(format!("{}/login/link/{link}", server.base))
            .send()
            .await
            .expect("link");
        let set = r.headers()["set-cookie"]
            .to_str()
            .expect("cookie")
            .to_owned();
        let cookie = set.split(';').next().expect("pair").to_owned();
        let html = client
            .get(format!("{}/annotate", server.base))
            .header("cookie", &cookie)
            .send()
            .await
            .expect("queue")
            .text()
            .await
            .expect("html");
        let start = html.find("name=\"csrf\" value=\"").expect("csrf") + 19;
        let csrf = html[start..start + 64].to_owned();
        server.kill();
        (cookie, csrf)
    };

    // item -> the answer its 2xx acknowledged; item -> drafts sent, and how many were acked.
    let mut answered: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut drafts: BTreeMap<String, (Vec<Value>, usize)> = BTreeMap::new();
    let mut next_item = 0;
    let items: Vec<String> = gt.keys().cloned().collect();
    for k in 0..kills() {
        let server = Server::start(&db).await;
        let writer = {
            let (client, base, cookie, csrf) = (
                client.clone(),
                server.base.clone(),
                cookie.clone(),
                csrf.clone(),
            );
            let (items, gt) = (items.clone(), gt.clone());
            let first = next_item;
            let seed: u64 = rng.random();
            tokio::spawn(async move {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let mut log: Vec<(String, Value, bool, bool)> = Vec::new();
                let mut position = first;
                while position < items.len() {
                    let item = &items[position];
                    let labels = &gt[item];
                    let full = rng.random_bool(0.5);
                    let slots: Vec<Value> = labels
                        .iter()
                        .enumerate()
                        .map(|(i, l)| {
                            if full || i == 0 {
                                json!(l)
                            } else {
                                Value::Null
                            }
                        })
                        .collect();
                    let draft = json!({"slots": slots, "counts": {"placements": 1, "swaps": 0, "clears": 0, "undos": 0}});
                    let finish = full && rng.random_bool(0.6);
                    let path = if finish { "submit" } else { "draft" };
                    let sent = client
                        .post(format!("{base}/annotate/mini/{item}/{path}"))
                        .header("cookie", &cookie)
                        .header("x-csrf-token", &csrf)
                        .json(&draft)
                        .send()
                        .await;
                    let Ok(reply) = sent else {
                        // The kill: this write may or may not have landed.
                        log.push((item.clone(), draft, finish, false));
                        break;
                    };
                    if reply.status() == 409 {
                        // Finished by a submit whose reply the last kill cut.
                        position += 1;
                        continue;
                    }
                    assert!(
                        reply.status().is_success(),
                        "{item}/{path}: {}",
                        reply.status()
                    );
                    log.push((item.clone(), draft, finish, true));
                    if finish {
                        position += 1;
                    }
                    // A person's pace, so the queue lasts through every kill.
                    tokio::time::sleep(Duration::from_millis(rng.random_range(0..12))).await;
                }
                (log, position)
            })
        };
        let at = Duration::from_millis(rng.random_range(5..300));
        tokio::time::sleep(at).await;
        server.kill();
        let (log, position) = writer.await.expect("writer");
        next_item = position;
        for (item, draft, finish, ok) in log {
            if finish && ok {
                let answer = draft["slots"]
                    .as_array()
                    .expect("slots")
                    .iter()
                    .map(|v| v.as_u64().expect("label"))
                    .collect();
                answered.insert(item, answer);
            } else {
                let entry = drafts.entry(item).or_default();
                entry.0.push(draft["slots"].clone());
                if ok && !finish {
                    entry.1 = entry.0.len();
                }
            }
        }

        let pool = open(&db).await;
        let after = format!("annotation kill {k} at {at:?}");
        check_database(&pool, &after).await;
        let stored: BTreeMap<String, Option<String>> =
            sqlx::query_as::<_, (String, Option<String>)>(
                "SELECT i.item_id, a.answer FROM annotations a JOIN items i ON i.id = a.item",
            )
            .fetch_all(&pool)
            .await
            .expect("annotations")
            .into_iter()
            .collect();
        for (item, answer) in &answered {
            let stored = stored
                .get(item)
                .unwrap_or_else(|| panic!("{after}: the acknowledged answer of {item} is lost"));
            let stored: Vec<u64> =
                serde_json::from_str(stored.as_deref().expect("an answer")).expect("json");
            assert_eq!(&stored, answer, "{after}: {item}");
        }
        let stored_drafts: BTreeMap<String, String> = sqlx::query_as::<_, (String, String)>(
            "SELECT i.item_id, d.slots FROM drafts d JOIN items i ON i.id = d.item",
        )
        .fetch_all(&pool)
        .await
        .expect("drafts")
        .into_iter()
        .collect();
        for (item, (sent, acked)) in &drafts {
            if stored.contains_key(item) {
                continue;
            }
            // A save acknowledged is there, or a later one sent after it (which may have
            // landed without its reply).
            if *acked > 0 {
                let slots: Value = serde_json::from_str(
                    stored_drafts
                        .get(item)
                        .unwrap_or_else(|| panic!("{after}: the draft of {item} is lost")),
                )
                .expect("json");
                assert!(
                    sent[acked - 1..].contains(&slots),
                    "{after}: the draft of {item} is {slots}, not one sent since the last acknowledged"
                );
            }
        }
        pool.close().await;
    }
    eprintln!(
        "crash annotations: {} kills, {} answers and {} drafted items checked",
        kills(),
        answered.len(),
        drafts.len()
    );
    // The survival checks above held something: answers and draft saves were acknowledged
    // before kills.
    let acked_drafts = drafts.values().filter(|(_, acked)| *acked > 0).count();
    assert!(
        !answered.is_empty() && acked_drafts > 0,
        "{} answers and {acked_drafts} draft saves acknowledged: nothing was checked",
        answered.len()
    );
}

/// Kills per server-side job (`ENACT_CRASH_JOB_KILLS`, default 10).
fn job_kills() -> usize {
    std::env::var("ENACT_CRASH_JOB_KILLS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10)
}

/// The lease the job trials' servers hold their jobs by (`serve --job-lease`, in seconds): a
/// restarted server takes a job over once its killed predecessor's lease has run out, at its
/// next look at the queue (every second). Short, so that ten kills take seconds rather than
/// minutes; three renewals long (one every half second), so that a renewal a loaded machine
/// delays does not lose it.
const JOB_LEASE: &str = "1.5";

/// The longest any one wait of a job trial may take before it fails saying what it saw: far
/// beyond a takeover (a lease and a poll) or any unit of work on a loaded two-core machine.
const JOB_DEADLINE: Duration = Duration::from_secs(90);

/// The servers of one job trial: all on one database (a SQLite file, or a fresh PostgreSQL
/// database when `ENACT_HUB_TEST_POSTGRES` is set), with one signing key and one log.
struct JobServers {
    db: PathBuf,
    pool: store::Pool,
    args: Vec<String>,
    log: PathBuf,
}

impl JobServers {
    async fn new(dir: &TempDir, extra: &[String]) -> JobServers {
        let (pool, db) = helpers::fresh_db_located(dir).await;
        let mut args = vec![
            "--job-lease".to_owned(),
            JOB_LEASE.to_owned(),
            "--signing-key".to_owned(),
            dir.path().join("signing-key").display().to_string(),
        ];
        args.extend_from_slice(extra);
        JobServers {
            db,
            pool,
            args,
            log: dir.path().join("servers.log"),
        }
    }

    async fn start(&self) -> Server {
        Server::start_with(&self.db, &self.args, Some(&self.log)).await
    }

    /// The end of the servers' log, for a failure's message.
    fn log_tail(&self) -> String {
        let log = std::fs::read_to_string(&self.log).unwrap_or_default();
        let lines: Vec<&str> = log.lines().collect();
        let tail = lines[lines.len().saturating_sub(40)..].join("\n");
        format!("the servers' log ends:\n{tail}")
    }

    /// POSTs `body` to `path` of `server` as `token`; the reply's JSON, which must come with
    /// `status`.
    async fn post(&self, server: &Server, path: &str, token: &str, body: &Value) -> Value {
        let reply = reqwest::Client::new()
            .post(format!("{}{path}", server.base))
            .bearer_auth(token)
            .json(body)
            .send()
            .await
            .unwrap_or_else(|e| panic!("POST {path}: {e}"));
        let status = reply.status();
        let json: Value = reply.json().await.expect("a JSON reply");
        assert_eq!(status, 202, "POST {path}: {json}");
        json
    }
}

/// The database checks after every kill of a job trial: SQLite's file checks
/// ([`check_database`]). PostgreSQL checks foreign keys at each commit and has no file a kill
/// can tear; only a constraint left unvalidated would escape it.
async fn check_job_database(pool: &store::Pool, after: &str) {
    match pool {
        store::Pool::Sqlite(pool) => check_database(pool, after).await,
        store::Pool::Pg(_) => {
            let unvalidated = helpers::count(
                pool,
                "SELECT count(*) FROM pg_constraint WHERE NOT convalidated",
            )
            .await;
            assert_eq!(unvalidated, 0, "after {after}: unvalidated constraints");
        }
    }
}

/// `SELECT count(*) …` with one integer parameter, on either database.
async fn count_with(pool: &store::Pool, sql: &str, bind: i64) -> i64 {
    helpers::db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, i64>(sql).bind(bind)
    )
    .unwrap_or_else(|e| panic!("{sql}: {e}"))
}

/// Audit entries of `action` on `target`.
async fn audit_entries(pool: &store::Pool, action: &str, target: &str) -> i64 {
    helpers::db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, i64>(
            "SELECT count(*) FROM audit_log WHERE action = $1 AND target = $2"
        )
        .bind(action)
        .bind(target)
    )
    .expect("audit")
}

/// A job's row as the trial sees it.
#[derive(Debug)]
struct JobSeen {
    state: String,
    lease_owner: Option<String>,
    attempts: i64,
    /// Shown (through `Debug`) when a wait fails.
    #[allow(dead_code)]
    last_error: Option<String>,
    progress: Option<String>,
    /// Shown (through `Debug`) when a wait fails: against `now_ms`, whether the lease ran out.
    #[allow(dead_code)]
    lease_until_ms: Option<i64>,
    #[allow(dead_code)]
    now_ms: i64,
}

impl JobSeen {
    fn ended(&self) -> bool {
        ["done", "failed", "cancelled"].contains(&self.state.as_str())
    }

    /// Whether the server with process id `pid` holds the lease (owners are
    /// `host:pid:random`).
    fn held_by(&self, pid: u32) -> bool {
        self.lease_owner
            .as_deref()
            .is_some_and(|owner| owner.contains(&format!(":{pid}:")))
    }

    fn progress(&self) -> Value {
        serde_json::from_str(self.progress.as_deref().unwrap_or("null")).expect("JSON progress")
    }
}

async fn job_seen(pool: &store::Pool, job: i64) -> JobSeen {
    type Row = (
        String,
        Option<String>,
        i64,
        Option<String>,
        Option<String>,
        Option<i64>,
    );
    let (state, lease_owner, attempts, last_error, progress, lease_until_ms) = helpers::db!(
        pool,
        fetch_one,
        sqlx::query_as::<_, Row>(
            "SELECT state, lease_owner, attempts, last_error, progress, lease_until_ms \
             FROM jobs WHERE id = $1"
        )
        .bind(job)
    )
    .expect("the job");
    JobSeen {
        state,
        lease_owner,
        attempts,
        last_error,
        progress,
        lease_until_ms,
        now_ms: enact_hub::app::jobs::now_ms(),
    }
}

/// What a job has durably done so far, read from the database: kills are aimed at random
/// points of it, so that they fall while the job works whatever the machine's speed.
#[derive(Debug, Clone, Copy)]
enum Gauge {
    /// Items of the run stored.
    RunItems(i64),
    /// Submissions at the current metric version.
    Rescored,
    /// Records of the import's committed batches, or of the dataset once it has landed.
    ImportedRows,
}

impl Gauge {
    async fn read(self, pool: &store::Pool) -> i64 {
        match self {
            Gauge::RunItems(run) => {
                count_with(
                    pool,
                    "SELECT count(*) FROM model_run_items WHERE run = $1",
                    run,
                )
                .await
            }
            Gauge::Rescored => {
                count_with(
                    pool,
                    "SELECT count(*) FROM submissions WHERE metric_version >= $1",
                    i64::from(METRIC_VERSION),
                )
                .await
            }
            Gauge::ImportedRows => {
                helpers::count(
                    pool,
                    "SELECT coalesce((SELECT max(rows_done) FROM staged_imports), \
                     (SELECT count(*) FROM items i JOIN datasets d ON d.id = i.dataset_id \
                      WHERE d.name = 'main'))",
                )
                .await
            }
        }
    }
}

/// Where a trial's kills fall: once the server has taken the job over, after the gauge has
/// grown by a random amount up to `most` (none, one time in four), and a random moment under
/// `jitter` more.
#[derive(Debug, Clone, Copy)]
struct Aim {
    gauge: Gauge,
    most: i64,
    jitter: Duration,
}

/// Lets `server` take `job` over and work it until the moment `aim` draws, then SIGKILLs it.
/// Returns what the kill was, for messages. Fails when the job ends first (the trial's job is
/// too short for its kills) or a wait passes [`JOB_DEADLINE`].
async fn kill_mid_job(
    servers: &JobServers,
    server: Server,
    job: i64,
    aim: Aim,
    rng: &mut ChaCha8Rng,
    label: &str,
) -> String {
    let pid = server.child.id();
    let deadline = Instant::now() + JOB_DEADLINE;
    loop {
        let seen = job_seen(&servers.pool, job).await;
        if seen.held_by(pid) && seen.state == "running" {
            break;
        }
        assert!(
            !seen.ended(),
            "{label}: the job ended before this kill: {seen:?}; the trial's job is too short \
             for its kills"
        );
        if Instant::now() >= deadline {
            let report = server.report().await;
            panic!(
                "{label}: the restarted server (pid {pid}) did not take the job over within \
                 {JOB_DEADLINE:?}: {seen:?}\n{report}\n{}",
                servers.log_tail()
            );
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let from = aim.gauge.read(&servers.pool).await;
    let step = if rng.random_bool(0.25) {
        0
    } else {
        rng.random_range(1..=aim.most.max(1))
    };
    loop {
        let now = aim.gauge.read(&servers.pool).await;
        if now >= from + step {
            break;
        }
        let seen = job_seen(&servers.pool, job).await;
        assert!(
            !seen.ended(),
            "{label}: the job ended before this kill: {seen:?}; the trial's job is too short \
             for its kills"
        );
        assert!(
            seen.held_by(pid) && seen.state == "running",
            "{label}: the server (pid {pid}) stopped working the job (it failed, or lost its \
             lease): {seen:?}\n{}",
            servers.log_tail()
        );
        assert!(
            Instant::now() < deadline,
            "{label}: {:?} stayed at {now} (from {from}, waiting for {}) for {JOB_DEADLINE:?}: \
             {seen:?}\n{}",
            aim.gauge,
            from + step,
            servers.log_tail()
        );
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let jitter = Duration::from_micros(
        rng.random_range(0..=u64::try_from(aim.jitter.as_micros()).unwrap_or(u64::MAX)),
    );
    tokio::time::sleep(jitter).await;
    server.kill();
    format!(
        "{label} ({:?} +{step} from {from}, then {jitter:?})",
        aim.gauge
    )
}

/// Starts a server once more, waits until `job` has ended and stops it; the job's row.
async fn run_job_to_end(servers: &JobServers, job: i64, label: &str) -> JobSeen {
    let server = servers.start().await;
    let deadline = Instant::now() + JOB_DEADLINE;
    let seen = loop {
        let seen = job_seen(&servers.pool, job).await;
        if seen.ended() {
            break seen;
        }
        assert!(
            Instant::now() < deadline,
            "{label}: the job did not end within {JOB_DEADLINE:?} after the last restart: \
             {seen:?}\n{}",
            servers.log_tail()
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    server.kill();
    assert_eq!(
        seen.state,
        "done",
        "{label}: the job ended {seen:?}\n{}",
        servers.log_tail()
    );
    seen
}

/// Answers every item right at once (as [`standin::StandIn`] scripts are keyed: by the item's
/// first image).
fn right_answers(
    root: &Path,
    records: &[Value],
) -> std::collections::HashMap<String, (String, Vec<standin::Step>)> {
    records
        .iter()
        .map(|r| {
            let first = root.join(r["images"][0].as_str().expect("image path"));
            let png = std::fs::read(&first).expect("the first image");
            let gt: Vec<u64> = r["gt_answer"]
                .as_array()
                .expect("gt")
                .iter()
                .map(|v| v.as_u64().expect("label"))
                .collect();
            (
                standin::item_key(&png),
                (
                    r["id"].as_str().expect("id").to_owned(),
                    vec![standin::Step::Answer(format!("The order is {gt:?}"))],
                ),
            )
        })
        .collect()
}

/// A model run worked by the server against the stand-in endpoint, the server killed at random
/// moments while the run asks and stores: after every kill each stored item is stored once (one
/// reply recorded, one attempt) and no submission or audit entry is doubled; after the restarts
/// the run finishes with every item answered exactly once, one submission with a verdict per
/// item, and the endpoint asked again at most what was in flight at each kill.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_model_run_killed_at_random_answers_every_item_once() {
    const CONCURRENCY: i64 = 4;
    let began = Instant::now();
    let mut rng = rng("model run job");
    let kills = job_kills();
    let dir = TempDir::new().expect("tempdir");
    let root = dir.path().join("release");
    // 180 items: fewer than 251, so that each one's first frame, by which the stand-in knows
    // it, is its own.
    let records = helpers::write_balanced_release(&root, &[3, 4, 5], 30);
    let items = records.len() as i64;
    let servers = JobServers::new(&dir, &[]).await;
    helpers::import(&servers.pool, &root, &helpers::options("mini")).await;
    let (_, admin) = helpers::api_token(&servers.pool, "root", Role::Admin, None, None).await;
    // Each reply after a model's pause, so that the run keeps CONCURRENCY requests in flight
    // and takes seconds, whatever the machine.
    let latency = Duration::from_millis(100);
    let standin = standin::StandIn::start(standin::StandInConfig {
        scripts: right_answers(&root, &records),
        latency,
        ..standin::StandInConfig::default()
    })
    .await;

    let first = servers.start().await;
    let started = servers
        .post(
            &first,
            "/api/v1/admin/runs",
            &admin,
            &json!({
                "dataset": "mini", "endpoint": standin.endpoint(), "model": "standin-vl",
                "name": "crash", "temperature": 0, "concurrency": CONCURRENCY,
                "timeout_s": 30, "submit_as": "Stand-in",
            }),
        )
        .await;
    let run = started["run"].as_i64().expect("a run id");
    let job = started["job"].as_i64().expect("a job id");
    let aim = Aim {
        gauge: Gauge::RunItems(run),
        most: items / (2 * kills.max(1) as i64),
        jitter: latency,
    };
    let pool = &servers.pool;
    // item row -> the reply stored for it, as first seen after a kill.
    let mut stored: BTreeMap<i64, Option<String>> = BTreeMap::new();
    let mut in_flight_at_kills = Vec::new();
    let mut first = Some(first);
    for k in 0..kills {
        let server = match first.take() {
            Some(server) => server,
            None => servers.start().await,
        };
        let after = kill_mid_job(
            &servers,
            server,
            job,
            aim,
            &mut rng,
            &format!("model run kill {k}"),
        )
        .await;
        check_job_database(pool, &after).await;
        let twice = count_with(
            pool,
            "SELECT count(*) FROM model_run_items WHERE run = $1 \
             AND (state != 'answered' OR attempts != 1)",
            run,
        )
        .await;
        assert_eq!(twice, 0, "{after}: items asked twice or failed");
        let now: Vec<(i64, Option<String>)> = helpers::db!(
            pool,
            fetch_all,
            sqlx::query_as("SELECT item, response FROM model_run_items WHERE run = $1").bind(run)
        )
        .expect("run items");
        for (item, response) in &now {
            if let Some(before) = stored.get(item) {
                assert_eq!(
                    before, response,
                    "{after}: item {item}'s stored reply changed"
                );
            }
        }
        let asked = standin.calls().len() as i64;
        in_flight_at_kills.push(asked - now.len() as i64);
        stored.extend(now);
        let submissions = helpers::count(pool, "SELECT count(*) FROM submissions").await;
        assert!(submissions <= 1, "{after}: {submissions} submissions");
        assert_eq!(
            helpers::count(
                pool,
                "SELECT count(*) FROM audit_log WHERE action = 'submission.create'"
            )
            .await,
            submissions,
            "{after}: audit entries and submissions differ"
        );
        assert_eq!(
            audit_entries(pool, "run.start", "run crash").await,
            1,
            "{after}: the run's start is logged once"
        );
    }

    let seen = run_job_to_end(&servers, job, "the model run").await;
    let after = "the finished model run";
    check_job_database(pool, after).await;
    let answered_once = count_with(
        pool,
        "SELECT count(*) FROM model_run_items WHERE run = $1 \
         AND state = 'answered' AND attempts = 1",
        run,
    )
    .await;
    let rows = count_with(
        pool,
        "SELECT count(*) FROM model_run_items WHERE run = $1",
        run,
    )
    .await;
    assert_eq!(
        (rows, answered_once),
        (items, items),
        "{after}: (items stored, answered once) of {items}"
    );
    let submission: i64 = helpers::db!(
        pool,
        fetch_one,
        sqlx::query_scalar::<_, Option<i64>>("SELECT submission FROM model_runs WHERE id = $1")
            .bind(run)
    )
    .expect("the run")
    .unwrap_or_else(|| panic!("{after}: no submission ({seen:?})"));
    assert_eq!(
        helpers::count(pool, "SELECT count(*) FROM submissions").await,
        1,
        "{after}: one submission"
    );
    let verdicts = count_with(
        pool,
        "SELECT count(*) FROM submission_items WHERE submission = $1",
        submission,
    )
    .await;
    let right = count_with(
        pool,
        "SELECT count(*) FROM submission_items WHERE submission = $1 AND exact_match",
        submission,
    )
    .await;
    assert_eq!(
        (verdicts, right),
        (items, items),
        "{after}: (verdicts, right) of {items}"
    );
    assert_eq!(audit_entries(pool, "run.start", "run crash").await, 1);
    assert_eq!(
        audit_entries(
            pool,
            "submission.create",
            &format!("submission {submission}")
        )
        .await,
        1,
        "{after}: the submission's audit entry"
    );
    assert_eq!(
        helpers::count(
            pool,
            "SELECT count(*) FROM audit_log WHERE action = 'submission.create'"
        )
        .await,
        1
    );
    // The endpoint: every item asked, and again at most what was in flight at each kill.
    assert!(
        standin.problems().is_empty(),
        "requests not as the client builds them: {:?}",
        standin.problems()
    );
    let calls = standin.calls();
    for r in &records {
        let id = r["id"].as_str().expect("id");
        assert!(calls.contains_key(id), "{after}: {id} was never asked");
    }
    let asked = standin.total_requests() as i64;
    let most = items + kills as i64 * CONCURRENCY;
    let mut again: Vec<(&String, usize)> = calls
        .iter()
        .filter(|(_, c)| c.requests > 1)
        .map(|(id, c)| (id, c.requests))
        .collect();
    again.sort();
    assert!(
        asked <= most,
        "{after}: the endpoint was asked {asked} times for {items} items over {kills} kills \
         (at most {most}); asked more than once: {again:?}"
    );
    eprintln!(
        "crash model run job: {kills} kills, {asked} requests for {items} items ({} asked \
         again; unstored asks at each kill {in_flight_at_kills:?}), job attempts {}, {:.1?}",
        asked - items,
        seen.attempts,
        began.elapsed()
    );
}

/// Scores of every submission, by id, exactly as stored.
async fn stored_scores(pool: &store::Pool) -> BTreeMap<i64, String> {
    helpers::db!(
        pool,
        fetch_all,
        sqlx::query_as::<_, (i64, String)>("SELECT id, scores FROM submissions")
    )
    .expect("scores")
    .into_iter()
    .collect()
}

/// A rescore of every stored submission worked by the server, killed at random moments while
/// it writes: after every kill each submission is wholly at the old version or wholly rescored
/// (its scores as they were, a verdict per item, and one signed statement more than it had),
/// and the rescore's audit entry is not doubled; after the restarts every submission is
/// rescored exactly once and the rescore is logged exactly once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_rescore_killed_at_random_rescores_every_submission_once() {
    const SUBMISSIONS: usize = 160;
    let began = Instant::now();
    let mut rng = rng("rescore job");
    let kills = job_kills();
    let dir = TempDir::new().expect("tempdir");
    let root = dir.path().join("release");
    let records = release(&root, 10);
    let items = records.len() as i64;
    let servers = JobServers::new(&dir, &[]).await;
    let pool = &servers.pool;
    helpers::import(pool, &root, &helpers::options("mini")).await;
    let (_, admin) = helpers::api_token(pool, "root", Role::Admin, None, None).await;
    let (_, team) = helpers::api_token(pool, "team", Role::Submitter, None, None).await;

    let first = servers.start().await;
    let client = reqwest::Client::new();
    for n in 0..SUBMISSIONS {
        let reply = client
            .post(format!(
                "{}/api/v1/datasets/mini/submissions?model=m{n}",
                first.base
            ))
            .bearer_auth(&team)
            .body(answers(&records, &[n % records.len()]))
            .send()
            .await
            .expect("submit");
        assert_eq!(reply.status(), 201, "submission {n}");
    }
    let scores = stored_scores(pool).await;
    // As a migration raising the metric version leaves them.
    helpers::db!(
        pool,
        execute,
        sqlx::query("UPDATE submissions SET metric_version = 1")
    )
    .expect("age the submissions");
    let statements = "SELECT count(*) FROM submissions s WHERE \
         (SELECT count(*) FROM submission_statements t WHERE t.submission = s.id) \
         != CASE WHEN s.metric_version >= $1 THEN 2 ELSE 1 END";
    let verdictless = "SELECT count(*) FROM submissions s WHERE \
         (SELECT count(*) FROM submission_items i WHERE i.submission = s.id) != $1";
    let current = i64::from(METRIC_VERSION);
    assert_eq!(
        count_with(pool, statements, current).await,
        0,
        "a submission is made with one signed statement"
    );
    let queued = servers
        .post(
            &first,
            "/api/v1/admin/rescore",
            &admin,
            &json!({"dataset": "mini"}),
        )
        .await;
    let job = queued["job"].as_i64().expect("a job id");
    let aim = Aim {
        gauge: Gauge::Rescored,
        most: (SUBMISSIONS / (2 * kills.max(1))) as i64,
        jitter: Duration::from_millis(20),
    };
    let mut first = Some(first);
    let mut rescored_at_kills = Vec::new();
    for k in 0..kills {
        let server = match first.take() {
            Some(server) => server,
            None => servers.start().await,
        };
        let after = kill_mid_job(
            &servers,
            server,
            job,
            aim,
            &mut rng,
            &format!("rescore kill {k}"),
        )
        .await;
        check_job_database(pool, &after).await;
        assert_eq!(
            count_with(pool, verdictless, items).await,
            0,
            "{after}: a submission without a verdict per item"
        );
        assert_eq!(
            count_with(pool, statements, current).await,
            0,
            "{after}: a submission rescored without its statement, or with two"
        );
        assert_eq!(
            count_with(
                pool,
                "SELECT count(*) FROM submissions WHERE metric_version NOT IN (1, $1)",
                current
            )
            .await,
            0
        );
        assert_eq!(
            stored_scores(pool).await,
            scores,
            "{after}: scores changed by a rescore under the same rules"
        );
        let logged = audit_entries(pool, "metric.rescore", "dataset mini").await;
        assert!(logged <= 1, "{after}: the rescore logged {logged} times");
        rescored_at_kills.push(Gauge::Rescored.read(pool).await);
    }

    let seen = run_job_to_end(&servers, job, "the rescore").await;
    let after = "the finished rescore";
    check_job_database(pool, after).await;
    assert_eq!(
        Gauge::Rescored.read(pool).await,
        SUBMISSIONS as i64,
        "{after}: submissions left at the old version"
    );
    assert_eq!(count_with(pool, verdictless, items).await, 0, "{after}");
    assert_eq!(
        count_with(pool, statements, current).await,
        0,
        "{after}: every submission has its statement and the rescore's"
    );
    assert_eq!(stored_scores(pool).await, scores, "{after}");
    assert_eq!(
        audit_entries(pool, "metric.rescore", "dataset mini").await,
        1,
        "{after}: the rescore is logged once"
    );
    let summary = seen.progress();
    assert_eq!(summary["failures"], json!([]), "{after}: {summary}");
    assert_eq!(summary["stopped"], false, "{after}: {summary}");
    eprintln!(
        "crash rescore job: {kills} kills, {SUBMISSIONS} submissions rescored once (rescored at \
         each kill {rescored_at_kills:?}; the last start {}), job attempts {}, {:.1?}",
        summary["submissions"],
        seen.attempts,
        began.elapsed()
    );
}

/// An import from the server's import folder worked by the server, killed at random moments
/// while it stages its batches: after every kill the dataset is absent or whole (identical,
/// by content hash, to an uninterrupted import's) and logged once exactly when it is there;
/// after the restarts it lands once, with nothing of its staging left.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_import_job_killed_at_random_lands_whole_once() {
    let began = Instant::now();
    let mut rng = rng("import job");
    let kills = job_kills();
    let dir = TempDir::new().expect("tempdir");
    let folder = dir.path().join("imports");
    // 1536 records: 24 batches of 64 lines, about twice what ten kills consume.
    let records = release(&folder.join("release"), 256);
    let items = records.len() as i64;
    let servers = JobServers::new(
        &dir,
        &["--import-dir".to_owned(), folder.display().to_string()],
    )
    .await;
    let pool = &servers.pool;
    let (_, admin) = helpers::api_token(pool, "root", Role::Admin, None, None).await;
    // The same release imported uninterrupted, in this process, for its content hash.
    let reference_dir = TempDir::new().expect("tempdir");
    let (reference, _) = helpers::fresh_db_located(&reference_dir).await;
    let timed = Instant::now();
    helpers::import(
        &reference,
        &folder.join("release"),
        &helpers::options("main"),
    )
    .await;
    let whole = timed.elapsed();
    let digest = dataset_digest(&reference, "main").await;

    let first = servers.start().await;
    let queued = servers
        .post(
            &first,
            "/api/v1/admin/imports",
            &admin,
            &json!({"path": "release", "dataset": "main"}),
        )
        .await;
    let job = queued["job"].as_i64().expect("a job id");
    let aim = Aim {
        gauge: Gauge::ImportedRows,
        most: 64,
        jitter: Duration::from_millis(30),
    };
    let mut first = Some(first);
    let mut rows_at_kills = Vec::new();
    for k in 0..kills {
        let server = match first.take() {
            Some(server) => server,
            None => servers.start().await,
        };
        let after = kill_mid_job(
            &servers,
            server,
            job,
            aim,
            &mut rng,
            &format!("import job kill {k}"),
        )
        .await;
        check_job_database(pool, &after).await;
        let landed =
            helpers::count(pool, "SELECT count(*) FROM datasets WHERE name = 'main'").await;
        if landed == 1 {
            assert_eq!(
                dataset_digest(pool, "main").await,
                digest,
                "{after}: the dataset landed, but not whole"
            );
        }
        assert_eq!(
            audit_entries(pool, "dataset.import", "dataset main").await,
            landed,
            "{after}: the import's audit entries"
        );
        let staged = helpers::count(pool, "SELECT count(*) FROM staged_imports").await;
        assert!(staged <= 1, "{after}: {staged} staged imports");
        rows_at_kills.push(Gauge::ImportedRows.read(pool).await);
    }

    let seen = run_job_to_end(&servers, job, "the import job").await;
    let after = "the finished import job";
    check_job_database(pool, after).await;
    let progress = seen.progress();
    assert_eq!(progress["outcome"], "imported", "{after}: {progress}");
    assert_eq!(
        dataset_digest(pool, "main").await,
        digest,
        "{after}: the dataset differs from an uninterrupted import's"
    );
    assert_eq!(
        audit_entries(pool, "dataset.import", "dataset main").await,
        1,
        "{after}: the import is logged once"
    );
    assert_eq!(
        (
            helpers::count(pool, "SELECT count(*) FROM staged_imports").await,
            helpers::count(pool, "SELECT count(*) FROM datasets").await,
            helpers::count(pool, "SELECT count(*) FROM items").await,
        ),
        (0, 1, items),
        "{after}: (staged imports, datasets, items) left"
    );
    eprintln!(
        "crash import job: {kills} kills, {items} items landed whole once (rows committed at \
         each kill {rows_at_kills:?}; the last start wrote {} items), job attempts {}, an \
         uninterrupted import {whole:.1?}, {:.1?}",
        progress["report"]["items_written"],
        seen.attempts,
        began.elapsed()
    );
}
