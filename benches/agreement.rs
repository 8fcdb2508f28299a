//! Alpha plus a 1000-replicate item bootstrap on 3 × 240 and 3 × 10,000 ordinal data sets.
//! The data sets come from the shared vectors when present (the same ones the python anchors
//! were timed on), otherwise they are generated deterministically here.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use enact_hub::core::agreement::{
    BootstrapConfig, MeasurementLevel, PreparedAlpha, ReliabilityData, parse_reliability_json,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[path = "../tests/support/fixtures.rs"]
mod fixtures;

fn fixtures_dir() -> Option<PathBuf> {
    fixtures::shared_fixtures()
}

/// The named vector's data from the shared fixtures, if they are there.
fn fixture_data(name: &str) -> Option<ReliabilityData> {
    let text = std::fs::read_to_string(fixtures_dir()?.join("kalpha").join("vectors.json")).ok()?;
    let vectors: serde_json::Value = serde_json::from_str(&text).ok()?;
    let vector = vectors
        .as_array()?
        .iter()
        .find(|vector| vector["name"] == name)?;
    parse_reliability_json(&serde_json::json!({ "data": vector["data"] }).to_string()).ok()
}

/// Three coders on values 1..=10 who mostly agree with a hidden true value.
fn generated_data(units: usize) -> ReliabilityData {
    let mut rng = ChaCha8Rng::seed_from_u64(240);
    let truth: Vec<i32> = (0..units).map(|_| rng.random_range(1..=10)).collect();
    let rows = (0..3)
        .map(|_| {
            truth
                .iter()
                .map(|&value| {
                    let shift = if rng.random_bool(0.6) {
                        0
                    } else {
                        rng.random_range(-2..=2)
                    };
                    Some(f64::from((value + shift).clamp(1, 10)))
                })
                .collect()
        })
        .collect();
    ReliabilityData::from_coder_rows(rows).expect("generated rows have equal lengths")
}

fn data_set(units: usize) -> (ReliabilityData, &'static str) {
    let name = format!("synthetic_3x{units}_values_1_to_10_ordinal");
    match fixture_data(&name) {
        Some(data) => (data, "fixture"),
        None => (generated_data(units), "generated"),
    }
}

fn alpha_and_bootstrap(criterion: &mut Criterion) {
    let mut group = criterion.benchmark_group("ordinal alpha + 1000 bootstrap replicates");
    group.sample_size(10);
    for units in [240, 10_000] {
        let (data, origin) = data_set(units);
        let config = BootstrapConfig::default();
        group.bench_function(format!("3x{units} ({origin})"), |bencher| {
            bencher.iter(|| {
                let prepared = PreparedAlpha::new(black_box(&data), MeasurementLevel::Ordinal);
                black_box(
                    prepared
                        .bootstrap(&config)
                        .expect("default config is valid"),
                )
            })
        });
        group.bench_function(format!("3x{units} alpha only ({origin})"), |bencher| {
            bencher.iter(|| {
                black_box(
                    PreparedAlpha::new(black_box(&data), MeasurementLevel::Ordinal).estimate(),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, alpha_and_bootstrap);
criterion_main!(benches);
