//! Scoring speed at the size of the real benchmark (8,972 items), single-threaded, from
//! precomputed `ItemSignatures`. Uses the `enact-parity` fixture items (replicated) when present,
//! synthetic items otherwise.

use std::collections::{BTreeSet, HashMap};
use std::fs;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use enact_hub::core::error_analysis::analyse_strict;
use enact_hub::core::verifier::{
    Direction, ItemSignatures, ParsedAnswer, PerformanceReport, Permutation, PyValue, ScoredEntry,
    StepLength, StrictItem, View, VisibleCoverage, parse_answer_enact, score_strict_predictions,
    verify,
};
use serde_json::Value;

const DATASET_SIZE: usize = 8972;

/// One benchmark item with its stored signatures and a model answer.
struct BenchItem {
    id: String,
    direction: Direction,
    step_length: StepLength,
    ground_truth: Permutation,
    signatures: ItemSignatures,
    answer_text: String,
}

#[path = "../tests/support/fixtures.rs"]
mod fixtures;

fn fixtures_dir() -> Option<PathBuf> {
    let dir = fixtures::shared_fixtures()?.join("enact-parity");
    dir.join("reference/pair_signatures.jsonl")
        .is_file()
        .then_some(dir)
}

type PairSets =
    HashMap<(String, String, String), Result<(BTreeSet<String>, BTreeSet<String>), String>>;

fn fixture_items(dir: &Path) -> Vec<BenchItem> {
    let mut pairs: PairSets = HashMap::new();
    let set = |v: &Value| {
        v.as_array().map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(str::to_owned))
                .collect()
        })
    };
    for line in fs::read_to_string(dir.join("reference/pair_signatures.jsonl"))
        .expect("pairs")
        .lines()
    {
        let row: Value = serde_json::from_str(line).expect("row");
        let key = |k: &str| row[k].as_str().unwrap_or_default().to_owned();
        let sets = match (set(&row["visible"]), set(&row["full"])) {
            (Some(v), Some(f)) => Ok((v, f)),
            _ => Err(row["error"].to_string()),
        };
        pairs.insert((key("task_name"), key("from_frame"), key("to_frame")), sets);
    }
    // Answers of several fake models, cycled over the replicas.
    let models = [
        "perfect",
        "random",
        "adjswap",
        "duplicates",
        "length",
        "prose",
    ];
    let mut answers: HashMap<String, Vec<String>> = HashMap::new();
    for model in models {
        let path = dir.join(format!("predictions/enact_ordering_{model}.jsonl"));
        for line in fs::read_to_string(path).expect("predictions").lines() {
            let row: Value = serde_json::from_str(line).expect("prediction");
            if let (Some(id), Some(answer)) = (row["id"].as_str(), row["answer"].as_str()) {
                answers
                    .entry(id.to_owned())
                    .or_default()
                    .push(answer.to_owned());
            }
        }
    }
    let mut base = Vec::new();
    for line in fs::read_to_string(dir.join("QA/enact_ordering.jsonl"))
        .expect("QA")
        .lines()
    {
        let row: Value = serde_json::from_str(line).expect("QA row");
        let id = row["id"].as_str().expect("id").to_owned();
        let task = row["task_name"].as_str().expect("task").to_owned();
        let frames: Vec<String> = row["key_frame_ids"]
            .as_array()
            .expect("frames")
            .iter()
            .map(|f| f.as_str().expect("frame").to_owned())
            .collect();
        let gt: Vec<u8> = row["gt_answer"]
            .as_array()
            .expect("gt")
            .iter()
            .map(|x| x.as_u64().expect("label") as u8)
            .collect();
        let direction = if row["type"].as_str().unwrap_or_default().contains("inverse") {
            Direction::Inverse
        } else {
            Direction::Forward
        };
        // As stored at import: forward tables hold the visible sets of every pair (the error
        // analysis reads them), inverse tables the chronological ones.
        let coverage = match direction {
            Direction::Forward => VisibleCoverage::AllPairs,
            Direction::Inverse => VisibleCoverage::Chronological,
        };
        let signatures = ItemSignatures::build(&frames, coverage, |from, to, view| {
            if from == to {
                return Ok(BTreeSet::new());
            }
            match pairs.get(&(task.clone(), from.to_owned(), to.to_owned())) {
                Some(Ok((v, f))) => Ok(if view == View::Visible {
                    v.clone()
                } else {
                    f.clone()
                }),
                Some(Err(e)) => Err(e.clone()),
                None => Err("unknown pair".to_owned()),
            }
        });
        let answers = answers.remove(&id).unwrap_or_default();
        base.push((
            id,
            direction,
            Permutation::new(gt).expect("gt"),
            signatures,
            answers,
        ));
    }
    (0..DATASET_SIZE)
        .map(|k| {
            let (id, direction, gt, signatures, answers) = &base[k % base.len()];
            let answer = answers
                .get(k / base.len() % answers.len().max(1))
                .cloned()
                .unwrap_or_default();
            BenchItem {
                id: format!("{id}#{k}"),
                direction: *direction,
                step_length: gt.step_length().expect("step length"),
                ground_truth: gt.clone(),
                signatures: signatures.clone(),
                answer_text: answer,
            }
        })
        .collect()
}

/// Deterministic synthetic items: random permutations and random small signature sets.
fn synthetic_items() -> Vec<BenchItem> {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move |bound: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % bound
    };
    (0..DATASET_SIZE)
        .map(|k| {
            let states = 3 + (k % 8);
            let mut labels: Vec<u8> = (1..states as u8).collect();
            for i in (1..labels.len()).rev() {
                labels.swap(i, next(i as u64 + 1) as usize);
            }
            let mut answer = labels.clone();
            let (a, b) = (
                next(answer.len() as u64) as usize,
                next(answer.len() as u64) as usize,
            );
            answer.swap(a, b);
            let frames: Vec<String> = (0..states).map(|i| format!("{}", 100 * i + k)).collect();
            let pool: Vec<String> = (0..40).map(|s| format!("edge_add_obj{s}_Inside")).collect();
            let coverage = if k % 2 == 0 {
                VisibleCoverage::AllPairs
            } else {
                VisibleCoverage::Chronological
            };
            let signatures = ItemSignatures::build(&frames, coverage, |from, to, view| {
                if from == to {
                    return Ok(BTreeSet::new());
                }
                let seed =
                    from.len() * 31 + to.len() * 7 + from.bytes().map(usize::from).sum::<usize>();
                let size = 1 + seed % 4 + if view == View::Full { 2 } else { 0 };
                Ok((0..size)
                    .map(|i| pool[(seed + i * 13) % pool.len()].clone())
                    .collect())
            });
            let text: Vec<String> = answer.iter().map(u8::to_string).collect();
            BenchItem {
                id: format!("synthetic_{k}"),
                direction: if k % 2 == 0 {
                    Direction::Forward
                } else {
                    Direction::Inverse
                },
                step_length: StepLength::new(states).expect("3..=10"),
                ground_truth: Permutation::new(labels).expect("permutation"),
                signatures,
                answer_text: format!("The order is [{}].", text.join(", ")),
            }
        })
        .collect()
}

/// Nanoseconds this thread has spent on a CPU (Linux `schedstat`), if available.
fn thread_cpu_ns() -> Option<u64> {
    let text = fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

fn verify_all(items: &[BenchItem], answers: &[ParsedAnswer]) -> PerformanceReport {
    let mut entries = Vec::with_capacity(items.len());
    for (item, answer) in items.iter().zip(answers) {
        if let Ok(verdict) = verify(
            item.direction,
            &item.ground_truth,
            answer,
            Some(&item.signatures),
        ) {
            entries.push(ScoredEntry {
                group: Some(item.direction),
                states: item.step_length.states(),
                task_accuracy: verdict.task_accuracy,
                pairwise_accuracy: verdict.pairwise_accuracy.value(),
            });
        }
    }
    PerformanceReport::from_entries(&entries)
}

fn bench_scoring(c: &mut Criterion) {
    let (items, source) = match fixtures_dir() {
        Some(dir) => (
            fixture_items(&dir),
            "enact-parity fixture items, replicated",
        ),
        None => (synthetic_items(), "synthetic items (fixtures not present)"),
    };
    println!("benchmark input: {} {source}", items.len());
    let answers: Vec<ParsedAnswer> = items
        .iter()
        .map(|item| {
            parse_answer_enact(
                &PyValue::Str(item.answer_text.clone()),
                item.ground_truth.len(),
            )
            .unwrap_or_else(|| ParsedAnswer::from(&item.ground_truth))
        })
        .collect();
    let lines: Vec<String> = items
        .iter()
        .map(|item| {
            format!(
                "{{\"id\": {}, \"answer\": {}}}",
                PyValue::Str(item.id.clone()).to_json(false),
                PyValue::Str(item.answer_text.clone()).to_json(false)
            )
        })
        .collect();
    let dataset: Vec<StrictItem<'_>> = items
        .iter()
        .map(|item| StrictItem {
            id: &item.id,
            direction: item.direction,
            step_length: item.step_length,
            ground_truth: &item.ground_truth,
            signatures: Some(&item.signatures),
        })
        .collect();

    // Plain timings for the record, next to criterion's statistics. On a shared machine the
    // wall time includes waiting for a core, so the thread's own CPU time is printed too.
    let report = verify_all(&items, &answers);
    println!(
        "verified {} items (overall TA {:.4})",
        report.overall.as_ref().map_or(0, |g| g.totals.count),
        report
            .overall
            .as_ref()
            .map_or(0.0, |g| g.totals.task_accuracy),
    );
    let passes = 30;
    let (wall, cpu_before) = (Instant::now(), thread_cpu_ns());
    for _ in 0..passes {
        black_box(verify_all(black_box(&items), black_box(&answers)));
    }
    let wall_ms = wall.elapsed().as_secs_f64() * 1e3 / f64::from(passes);
    match (cpu_before, thread_cpu_ns()) {
        (Some(before), Some(after)) => println!(
            "verify pass: {wall_ms:.2} ms wall, {:.2} ms on-CPU (mean of {passes})",
            (after - before) as f64 / 1e6 / f64::from(passes)
        ),
        _ => println!("verify pass: {wall_ms:.2} ms wall (mean of {passes})"),
    }

    c.bench_function("verify_8972_items_from_item_signatures", |b| {
        b.iter(|| black_box(verify_all(black_box(&items), black_box(&answers))))
    });
    c.bench_function("strict_policy_8972_prediction_lines", |b| {
        b.iter(|| {
            black_box(
                score_strict_predictions(
                    &dataset,
                    lines.iter().enumerate().map(|(i, l)| (i + 1, l.as_str())),
                )
                .expect("scores"),
            )
        })
    });
    let scoring = score_strict_predictions(
        &dataset,
        lines.iter().enumerate().map(|(i, l)| (i + 1, l.as_str())),
    )
    .expect("scores");
    let analysis = analyse_strict(&dataset, &scoring);
    println!(
        "error analysis: {} answers analysed, {} errors",
        analysis.overall.analysed_answers, analysis.overall.errors
    );
    c.bench_function("error_analysis_8972_answers", |b| {
        b.iter(|| black_box(analyse_strict(black_box(&dataset), black_box(&scoring))))
    });
    c.bench_function("item_signatures_deserialise_8972", |b| {
        let stored: Vec<String> = items
            .iter()
            .map(|i| serde_json::to_string(&i.signatures).expect("serialise"))
            .collect();
        b.iter(|| {
            for text in &stored {
                black_box(serde_json::from_str::<ItemSignatures>(text).expect("deserialise"));
            }
        })
    });
}

criterion_group!(benches, bench_scoring);
criterion_main!(benches);
