//! How long a refused login takes: a wrong password for a real name, an unknown name, and a
//! name whose invite is unused. The three must match (SECURITY.md, "Annotators"): a difference
//! would tell an attacker which names exist. Each is `app::annotators::check_password` on a
//! SQLite database, the whole of the login's work but the form and the rate limit.
//!
//! `cargo bench --bench login`; the figures go in BENCHMARKS.md and SECURITY.md.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use enact_hub::app::{Hub, annotators};
use enact_hub::core::audit::Actor;
use enact_hub::store;

const PASSWORD: &str = "the real password of bob";

fn refused_logins(c: &mut Criterion) {
    let runtime = tokio::runtime::Runtime::new().expect("runtime");
    let dir = tempfile::tempdir().expect("temporary directory");
    let hub = runtime.block_on(async {
        let pool = store::open(&dir.path().join("bench.db"))
            .await
            .expect("database");
        let hub = Hub::from(pool);
        let operator = Actor::Operator("bench".to_owned());
        let bob = annotators::create(&hub, &operator, "bob", false)
            .await
            .expect("bob");
        annotators::accept_invite(&hub, &bob.invite_token, PASSWORD, PASSWORD)
            .await
            .expect("bob's password");
        annotators::create(&hub, &operator, "carol", false)
            .await
            .expect("carol, invited");
        annotators::prepare_login().await.expect("the dummy hash");
        hub
    });
    let mut group = c.benchmark_group("refused login");
    group.sample_size(30);
    group.measurement_time(Duration::from_secs(10));
    for (what, name) in [
        ("wrong password for a real name", "bob"),
        ("unknown name", "nobody-by-this-name"),
        ("invite unused", "carol"),
    ] {
        group.bench_function(what, |b| {
            b.iter(|| {
                let found = runtime
                    .block_on(annotators::check_password(
                        &hub,
                        black_box(name),
                        black_box("a wrong password"),
                    ))
                    .expect("check");
                assert_eq!(found, None);
            });
        });
    }
    group.finish();
}

criterion_group!(benches, refused_logins);
criterion_main!(benches);
