//! A leaderboard rebuild with 10,000 human answers on the demo dataset (scene-graph signatures
//! on every item): with each answer's verdict stored when it was finished, and with no verdict
//! stored, where every rebuild judges every answer again (what every rebuild did before
//! verdicts were stored, and what a database migrated from then does until it is rescored).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use enact_hub::app::{Hub, Lane, demo, leaderboard, rescore};
use enact_hub::core::annotation::{Outcome, Telemetry};
use enact_hub::core::audit::Actor;
use enact_hub::core::verifier::Permutation;
use enact_hub::store;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

const ANSWERS: usize = 10_000;

struct Setup {
    _dir: tempfile::TempDir,
    hub: Hub,
    dataset: store::datasets::Dataset,
}

/// The demo dataset with `ANSWERS` random answers spread over as many annotators as it takes,
/// each answering every item once, and their verdicts stored (by a rescore).
async fn setup() -> Setup {
    let dir = tempfile::tempdir().expect("temporary directory");
    let pool = store::open(&dir.path().join("bench.db"))
        .await
        .expect("database");
    let hub = Hub::from(pool.clone());
    demo::load(&hub).await.expect("demo dataset");
    let mut conn = pool.acquire().await.expect("connection");
    let dataset = store::datasets::by_name(&mut conn, demo::DEMO_DATASET)
        .await
        .expect("query")
        .expect("the demo dataset");
    let items = store::annotations::dataset_items(&mut conn, dataset.id)
        .await
        .expect("items");
    let mut rng = ChaCha8Rng::seed_from_u64(10_000);
    drop(conn);
    let mut tx = hub.write(Lane::Bulk).await.expect("transaction");
    let mut answered = 0;
    for annotator in 0.. {
        if answered == ANSWERS {
            break;
        }
        let id = store::annotations::create_annotator(
            &mut tx,
            &format!("bench-{annotator}"),
            false,
            &format!("invite-{annotator}"),
        )
        .await
        .expect("a new name");
        for item in items.iter().take(ANSWERS - answered) {
            let mut labels: Vec<u8> = (1..=item.step_length.actions() as u8).collect();
            labels.shuffle(&mut rng);
            let answer = Permutation::new(labels).expect("a permutation");
            store::annotations::finish(
                &mut tx,
                id,
                item.item,
                &Outcome::Answered(answer),
                &Telemetry::none(),
            )
            .await
            .expect("insert");
            answered += 1;
        }
    }
    tx.commit().await.expect("commit");
    rescore::rescore(&hub, &Actor::Server, Some(demo::DEMO_DATASET), &|_| {})
        .await
        .expect("verdicts stored");
    Setup {
        _dir: dir,
        hub,
        dataset,
    }
}

fn rebuild(c: &mut Criterion) {
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let setup = runtime.block_on(setup());
    let rows = runtime
        .block_on(leaderboard::rows(&setup.hub, &setup.dataset))
        .expect("rows");
    let human = rows.iter().find_map(|r| r.human).expect("the Human row");
    assert_eq!(human.answers, ANSWERS);

    let mut group = c.benchmark_group("leaderboard rebuild, 10,000 human answers");
    group.sample_size(20);
    group.bench_function("verdicts stored", |b| {
        b.iter(|| {
            runtime
                .block_on(leaderboard::rows(&setup.hub, black_box(&setup.dataset)))
                .expect("rows")
        })
    });
    runtime.block_on(async {
        let mut tx = setup.hub.write(Lane::Bulk).await.expect("transaction");
        store::annotations::forget_verdicts(&mut tx, setup.dataset.id)
            .await
            .expect("forget");
        tx.commit().await.expect("commit");
    });
    let judged = runtime
        .block_on(leaderboard::rows(&setup.hub, &setup.dataset))
        .expect("rows");
    assert_eq!(
        judged, rows,
        "stored and judged verdicts give the same board"
    );
    group.bench_function("every answer judged (no verdict stored)", |b| {
        b.iter(|| {
            runtime
                .block_on(leaderboard::rows(&setup.hub, black_box(&setup.dataset)))
                .expect("rows")
        })
    });
    group.finish();
}

criterion_group!(benches, rebuild);
criterion_main!(benches);
