//! `enact-hub backup` while submissions keep arriving, then `enact-hub restore`: the snapshot
//! passes SQLite's integrity check and holds every submission acknowledged before the backup
//! began; neither command overwrites a file. On PostgreSQL the snapshot is still a SQLite file,
//! and a restore copies it into an empty database.

use std::path::Path;
use std::process::Output;
use std::time::Instant;

use enact_hub::core::credentials::Role;

use crate::helpers::*;

/// `enact-hub backup --db DB --out OUT`.
fn backup(db: &Path, out: &Path) -> Output {
    enact_hub()
        .args(["backup", "--db"])
        .arg(db)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// `enact-hub restore [--replace] --from SNAPSHOT --db DB`.
fn restore(snapshot: &Path, db: &Path, replace: bool) -> Output {
    let mut command = enact_hub();
    command.arg("restore");
    if replace {
        command.arg("--replace");
    }
    command
        .arg("--from")
        .arg(snapshot)
        .arg("--db")
        .arg(db)
        .output()
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_backup_under_write_load_restores_every_acknowledged_write() {
    let (server, records) = spawn_app_with_release().await;
    let (_, token) = api_token(&server.pool, "team", Role::Admin, None, None).await;
    let server = std::sync::Arc::new(server);

    // Submissions, one after another, each with the moment its 201 arrived.
    // The writer says when ten are acknowledged, so the backup starts after
    // them however slow the machine is (counting rows would race the 201s).
    let (ten_acknowledged, mut ten) = tokio::sync::watch::channel(false);
    let writer = {
        let server = server.clone();
        let body = answers(&records, &[0]);
        tokio::spawn(async move {
            let mut acknowledged = Vec::new();
            for k in 0..60 {
                let reply = submit_to(
                    &server,
                    "mini",
                    &format!("model=m{k}"),
                    &token,
                    body.clone(),
                )
                .await;
                assert_eq!(reply.status, 201, "{}", reply.text);
                acknowledged.push((reply.id(), Instant::now()));
                if acknowledged.len() == 10 {
                    ten_acknowledged.send_replace(true);
                }
            }
            acknowledged
        })
    };
    // Let some writes land, then snapshot while the rest arrive.
    ten.wait_for(|ready| *ready).await.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let snapshot = dir.path().join("snapshot.db");
    let began = Instant::now();
    let out = backup(&server.db_path(), &snapshot);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("integrity ok"));
    let acknowledged = writer.await.unwrap();
    let before: Vec<i64> = acknowledged
        .iter()
        .filter(|(_, at)| *at < began)
        .map(|(id, _)| *id)
        .collect();
    assert!(
        before.len() >= 10,
        "{} writes before the backup",
        before.len()
    );

    // A backup never overwrites.
    let again = backup(&server.db_path(), &snapshot);
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("already exists"));

    // Restore into a new place, and check what it holds.
    let restored = match postgres_server() {
        Some(server) => std::path::PathBuf::from(new_postgres_database(&server).await),
        None => dir.path().join("restored.db"),
    };
    let out = restore(&snapshot, &restored, false);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pool = match postgres_server() {
        Some(_) => enact_hub::store::Pool::Pg(
            enact_hub::store::db::open_postgres(restored.to_str().unwrap(), 2)
                .await
                .unwrap(),
        ),
        None => {
            let pool = enact_hub::store::open(&restored).await.unwrap();
            let mut conn = pool.acquire().await.unwrap();
            assert_eq!(
                enact_hub::store::integrity_check(&mut conn).await.unwrap(),
                "ok"
            );
            enact_hub::store::Pool::Sqlite(pool)
        }
    };
    let ids: Vec<i64> = db!(
        pool,
        fetch_all,
        sqlx::query_scalar("SELECT id FROM submissions")
    )
    .unwrap();
    for id in &before {
        assert!(
            ids.contains(id),
            "submission {id}, acknowledged before the backup, is lost"
        );
    }
    // Each restored submission is whole: all its item verdicts came along.
    let items = records.len() as i64;
    let partial: i64 = db!(
        pool,
        fetch_one,
        sqlx::query_scalar(
            "SELECT count(*) FROM (SELECT submission, count(*) AS n FROM submission_items \
             GROUP BY submission) AS per_submission WHERE n != $1",
        )
        .bind(items)
    )
    .unwrap();
    assert_eq!(partial, 0);
    pool.close().await;

    // An existing database is refused, or moved aside when asked (a PostgreSQL one is only
    // ever restored into when empty).
    let refused = restore(&snapshot, &restored, false);
    assert!(!refused.status.success());
    let replaced = restore(&snapshot, &restored, true);
    if on_sqlite() {
        assert!(String::from_utf8_lossy(&refused.stderr).contains("--replace"));
        assert!(
            replaced.status.success(),
            "{}",
            String::from_utf8_lossy(&replaced.stderr)
        );
        assert!(dir.path().join("restored.db.before-restore").exists());
    } else {
        assert!(
            String::from_utf8_lossy(&refused.stderr).contains("only copied into an empty one"),
            "{}",
            String::from_utf8_lossy(&refused.stderr)
        );
        assert!(!replaced.status.success());
        assert!(String::from_utf8_lossy(&replaced.stderr).contains("createdb"));
    }
}

/// The snapshot transaction a backup (and migrate-db) reads in takes no write lock: a write
/// commits while it is open, and it goes on seeing the database as it was when it began.
#[tokio::test]
async fn a_snapshot_read_lets_writers_commit_and_sees_none_of_their_writes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pool = fresh_db(&dir).await;
    let before = count(&pool, "SELECT count(*) FROM audit_log").await;
    let mut snapshot = pool.begin_snapshot().await.expect("a snapshot");
    assert_eq!(audit_rows(&mut snapshot).await, before);

    // A write transaction takes the write lock: it would wait for a locking reader, then
    // fail as busy after the lock timeout.
    let mut write = pool
        .begin()
        .await
        .expect("the write lock while the snapshot is open");
    enact_hub::store::on_db!(&mut write, |c| sqlx::query(
        "INSERT INTO audit_log (actor_kind, actor, action, target) \
         VALUES ('operator', 'tests', 'backup.create', 'file x')"
    )
    .execute(&mut *c)
    .await
    .map(|_| ()))
    .expect("insert");
    write.commit().await.expect("commit beside the snapshot");

    assert_eq!(
        audit_rows(&mut snapshot).await,
        before,
        "the snapshot sees the database as it began"
    );
    snapshot.rollback().await.expect("end the snapshot");
    assert_eq!(
        count(&pool, "SELECT count(*) FROM audit_log").await,
        before + 1
    );
}

async fn audit_rows(tx: &mut enact_hub::store::PlainTx) -> i64 {
    enact_hub::store::on_db!(tx, |c| sqlx::query_scalar::<_, i64>(
        "SELECT count(*) FROM audit_log"
    )
    .fetch_one(&mut *c)
    .await)
    .expect("count the audit log")
}
