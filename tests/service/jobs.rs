//! The job mechanism: claimed by one worker at a time, leases renewed and taken over when they
//! run out, failures retried then failed, pause/resume/cancel, and a graceful stop that lets
//! go at once. The jobs here are the tests' own code under the `rescore` kind.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use enact_hub::app::jobs::{
    JobContext, JobControl, JobHandlers, JobId, JobKind, JobSettings, JobState, Worker,
};
use enact_hub::app::{AppError, Hub, jobs};
use enact_hub::core::audit::Actor;
use enact_hub::store::Pool;
use serde_json::json;
use tempfile::TempDir;

use crate::helpers::{db, fresh_db, tester};

fn fast() -> JobSettings {
    JobSettings {
        lease: Duration::from_millis(600),
        poll: Duration::from_millis(20),
        max_running: 4,
        max_attempts: 3,
        retry_base: Duration::from_millis(50),
    }
}

async fn enqueue(pool: &Pool, payload: serde_json::Value) -> JobId {
    let mut tx = crate::helpers::write_tx(pool).await;
    let id = jobs::enqueue(&mut tx, JobKind::Rescore, &payload, &tester())
        .await
        .expect("enqueued");
    tx.commit().await.expect("committed");
    id
}

async fn wait_for(hub: &Hub, id: JobId, state: JobState) -> jobs::JobRow {
    // A deadline in time, not a number of polls: each poll is slower on a loaded machine.
    let deadline = Instant::now() + Duration::from_secs(30);
    while Instant::now() < deadline {
        let job = jobs::get(hub, id).await.expect("read").expect("the job");
        if job.state == state {
            return job;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let job = jobs::get(hub, id).await.expect("read").expect("the job");
    panic!("{id} did not become {state:?} within 30 s; it is {job:?}");
}

/// The wall clock in milliseconds, as job leases count it.
fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_millis() as i64
}

/// Handlers under which each job counts its starts by owner-less key (its `n`), and does what
/// its payload says: `"finish"`, `"fail"`, or `"wait"` until asked to stop.
fn recording(starts: Arc<Mutex<BTreeMap<i64, u32>>>) -> JobHandlers {
    JobHandlers::default().with(JobKind::Rescore, move |hub, job: Arc<JobContext>| {
        let starts = Arc::clone(&starts);
        Box::pin(async move {
            let n = job.payload["n"].as_i64().unwrap_or(-1);
            *starts.lock().expect("lock").entry(n).or_default() += 1;
            match job.payload["do"].as_str() {
                Some("fail") => Err(AppError::internal("told to fail")),
                Some("wait") => {
                    let why = job.stopped().await;
                    job.progress(&hub, &json!({"stopped": format!("{why:?}")}))
                        .await?;
                    Ok(())
                }
                _ => {
                    job.progress(&hub, &json!({"done": n})).await?;
                    Ok(())
                }
            }
        })
    })
}

#[tokio::test]
async fn a_job_runs_once_and_records_its_progress() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let worker = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    let id = enqueue(&pool, json!({"n": 1, "do": "finish"})).await;
    let job = wait_for(&hub, id, JobState::Done).await;
    assert_eq!(job.attempts, 1);
    assert_eq!(job.progress.as_deref(), Some(r#"{"done":1}"#));
    assert!(job.finished_at.is_some() && job.lease_owner.is_none());
    worker.stop().await;
    assert_eq!(starts.lock().unwrap().get(&1), Some(&1));
}

#[tokio::test]
async fn two_workers_never_take_the_same_job() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let a = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    let b = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    let mut ids = Vec::new();
    for n in 0..40 {
        ids.push(enqueue(&pool, json!({"n": n, "do": "finish"})).await);
    }
    for id in ids {
        wait_for(&hub, id, JobState::Done).await;
    }
    a.stop().await;
    b.stop().await;
    let starts = starts.lock().unwrap();
    assert_eq!(starts.len(), 40);
    assert!(starts.values().all(|&n| n == 1), "{starts:?}");
}

#[tokio::test]
async fn a_failing_job_is_retried_then_failed_with_its_error() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let worker = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    let id = enqueue(&pool, json!({"n": 7, "do": "fail"})).await;
    let job = wait_for(&hub, id, JobState::Failed).await;
    worker.stop().await;
    assert_eq!(job.attempts, 3);
    assert_eq!(job.last_error.as_deref(), Some("told to fail"));
    assert_eq!(starts.lock().unwrap().get(&7), Some(&3));
}

#[tokio::test]
async fn a_dead_instances_job_is_taken_over_when_its_lease_runs_out() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let id = enqueue(&pool, json!({"n": 3, "do": "finish"})).await;
    // An instance that claimed it and died: its lease runs out in 2 s and is never renewed.
    let until = now_ms() + 2000;
    db!(
        pool,
        execute,
        sqlx::query(
            "UPDATE jobs SET state = 'running', lease_owner = 'dead', lease_until_ms = $1, \
             attempts = 1 WHERE id = $2"
        )
        .bind(until)
        .bind(id.0)
    )
    .unwrap();
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let worker = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    // Until the lease runs out nobody has started it: each look at the starts is checked
    // against the clock read after it, so a slow machine only makes fewer looks, never a
    // false alarm. At least one look falls inside the lease (it is 2 s long).
    let mut looks = 0;
    loop {
        let taken = !starts.lock().unwrap().is_empty();
        if now_ms() >= until {
            break;
        }
        assert!(!taken, "taken before the lease ran out");
        looks += 1;
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert!(looks > 0, "no look fell inside the lease");
    let job = wait_for(&hub, id, JobState::Done).await;
    worker.stop().await;
    assert_eq!(job.attempts, 2);
    assert_eq!(starts.lock().unwrap().get(&3), Some(&1));
}

#[tokio::test]
async fn paused_jobs_stop_and_resume_and_cancel_is_audited() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let worker = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), fast());
    let admin = Actor::Operator("admin".into());
    let id = enqueue(&pool, json!({"n": 5, "do": "wait"})).await;
    wait_for(&hub, id, JobState::Running).await;
    jobs::control(&hub, &admin, id, JobControl::Pause)
        .await
        .unwrap();
    // The job's code saw the pause at its next lease renewal and stopped; the state stays.
    for _ in 0..200 {
        let job = jobs::get(&hub, id).await.unwrap().unwrap();
        if job.lease_owner.is_none() {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let job = jobs::get(&hub, id).await.unwrap().unwrap();
    assert_eq!(job.state, JobState::Paused);
    assert_eq!(job.progress.as_deref(), Some(r#"{"stopped":"Paused"}"#));
    let refused = jobs::control(&hub, &admin, id, JobControl::Pause).await;
    assert!(
        matches!(&refused, Err(AppError::Conflict(m)) if m.contains("is paused")),
        "{refused:?}"
    );
    jobs::control(&hub, &admin, id, JobControl::Resume)
        .await
        .unwrap();
    wait_for(&hub, id, JobState::Running).await;
    // The job is running once a worker has claimed it; its code starts a moment later.
    let deadline = Instant::now() + Duration::from_secs(30);
    while starts.lock().unwrap().get(&5) != Some(&2) && Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert_eq!(starts.lock().unwrap().get(&5), Some(&2));
    jobs::control(&hub, &admin, id, JobControl::Cancel)
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let job = wait_for(&hub, id, JobState::Cancelled).await;
    assert!(job.finished_at.is_some());
    worker.stop().await;
    let actions = enact_hub::app::audit::list(
        &hub,
        enact_hub::core::audit::AuditFilter {
            action: Some("job".into()),
            limit: 100,
            ..Default::default()
        },
    )
    .await
    .unwrap();
    let actions: Vec<&str> = actions.iter().map(|e| e.action.as_str()).collect();
    assert_eq!(actions, ["job.cancel", "job.resume", "job.pause"]);
}

/// A job paused and resumed before its code noticed the pause is not started a second time
/// beside the first: the resumed job waits for the first run to let go of its lease.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_resumed_before_its_code_stopped_never_runs_twice_at_once() {
    use std::sync::atomic::{AtomicUsize, Ordering};

    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    // (running now, most at once, starts)
    let counts = Arc::new((
        AtomicUsize::new(0),
        AtomicUsize::new(0),
        AtomicUsize::new(0),
    ));
    let seen = Arc::clone(&counts);
    let handlers = JobHandlers::default().with(JobKind::Rescore, move |_, job: Arc<JobContext>| {
        let counts = Arc::clone(&seen);
        Box::pin(async move {
            let now = counts.0.fetch_add(1, Ordering::SeqCst) + 1;
            counts.1.fetch_max(now, Ordering::SeqCst);
            counts.2.fetch_add(1, Ordering::SeqCst);
            // Works for 1.5 s unless told to stop, checking between units of work.
            for _ in 0..30 {
                if job.stop_requested().is_some() {
                    break;
                }
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
            counts.0.fetch_sub(1, Ordering::SeqCst);
            Ok(())
        })
    });
    let worker = Worker::spawn(hub.clone(), handlers, fast());
    let admin = Actor::Operator("admin".into());
    let id = enqueue(&pool, json!({"n": 7})).await;
    wait_for(&hub, id, JobState::Running).await;
    // Both before the next lease renewal (every 200 ms) tells the code about the pause.
    jobs::control(&hub, &admin, id, JobControl::Pause)
        .await
        .unwrap();
    jobs::control(&hub, &admin, id, JobControl::Resume)
        .await
        .unwrap();
    wait_for(&hub, id, JobState::Done).await;
    worker.stop().await;
    assert_eq!(counts.1.load(Ordering::SeqCst), 1, "ran twice at once");
    assert_eq!(
        counts.2.load(Ordering::SeqCst),
        2,
        "started again after the resume"
    );
}

#[tokio::test]
async fn a_graceful_stop_lets_go_at_once_for_the_next_instance() {
    let dir = TempDir::new().unwrap();
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    let starts = Arc::new(Mutex::new(BTreeMap::new()));
    let slow = JobSettings {
        lease: Duration::from_secs(60),
        ..fast()
    };
    let first = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), slow);
    let id = enqueue(&pool, json!({"n": 9, "do": "wait"})).await;
    wait_for(&hub, id, JobState::Running).await;
    first.stop().await;
    let job = jobs::get(&hub, id).await.unwrap().unwrap();
    assert_eq!(job.state, JobState::Queued);
    assert!(job.lease_owner.is_none());
    // The next instance takes it at once, not 60 s later when the lease would have run out.
    let second = Worker::spawn(hub.clone(), recording(Arc::clone(&starts)), slow);
    wait_for(&hub, id, JobState::Running).await;
    // The claim commits before the job's code starts and counts its start.
    for _ in 0..500 {
        if starts.lock().unwrap().get(&9) == Some(&2) {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert_eq!(starts.lock().unwrap().get(&9), Some(&2));
    second.stop().await;
}
