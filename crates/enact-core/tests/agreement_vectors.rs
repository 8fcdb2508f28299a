//! Parity with the shared Krippendorff's alpha vectors (`shared/fixtures/kalpha/vectors.json`):
//! every alpha (including undefined ones), the canonical intermediates, pairwise alphas, the
//! fixed-index bootstrap replicates, the spread of bootstrap intervals, and the ordering
//! encodings of the permutation example.

use std::collections::HashMap;

use enact_core::agreement::{
    AlphaUndefined, AnnotatedOrdering, BootstrapConfig, MeasurementLevel, OrderingAnnotations,
    OrderingEncoding, PreparedAlpha, ReliabilityData, krippendorff_alpha, pairwise_alphas,
    parse_reliability_json,
};
use serde_json::Value;

#[path = "../../../tests/support/fixtures.rs"]
mod fixtures;

fn vectors() -> Option<Vec<Value>> {
    let path = fixtures::fixture("kalpha/vectors.json")?;
    let text = std::fs::read_to_string(&path).unwrap();
    let Value::Array(vectors) = serde_json::from_str(&text).unwrap() else {
        panic!("{} is not a JSON list", path.display());
    };
    assert!(!vectors.is_empty(), "{} holds no vectors", path.display());
    Some(vectors)
}

fn name(vector: &Value) -> &str {
    vector["name"].as_str().unwrap()
}

fn level(vector: &Value) -> MeasurementLevel {
    vector["level"].as_str().unwrap().parse().unwrap()
}

fn tolerance(vector: &Value) -> f64 {
    if name(vector).contains("3x10000") {
        1e-9
    } else {
        1e-12
    }
}

/// The vector's data as reliability data; string values (whole answers written out) become
/// category numbers, which only nominal vectors use.
fn reliability(vector: &Value) -> ReliabilityData {
    let mut categories: HashMap<String, f64> = HashMap::new();
    let rows = vector["data"]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .map(|cell| match cell {
                    Value::Null => None,
                    Value::Number(number) => Some(number.as_f64().unwrap()),
                    Value::String(text) => {
                        assert_eq!(level(vector), MeasurementLevel::Nominal, "{}", name(vector));
                        let next = categories.len() as f64;
                        Some(*categories.entry(text.clone()).or_insert(next))
                    }
                    other => panic!("{}: unexpected cell {other}", name(vector)),
                })
                .collect()
        })
        .collect();
    ReliabilityData::from_coder_rows(rows).unwrap()
}

fn assert_close(what: &str, actual: Option<f64>, expected: f64, tolerance: f64) {
    let actual = actual.unwrap_or_else(|| panic!("{what}: undefined, expected {expected}"));
    assert!(
        (actual - expected).abs() <= tolerance,
        "{what}: {actual} differs from {expected} by {}",
        (actual - expected).abs()
    );
}

fn exact_rational(text: &str) -> f64 {
    let (numerator, denominator) = text.split_once('/').unwrap();
    numerator.parse::<f64>().unwrap() / denominator.parse::<f64>().unwrap()
}

#[test]
fn every_alpha_matches() {
    let Some(vectors) = vectors() else { return };
    let mut defined = 0;
    let mut undefined = 0;
    for vector in &vectors {
        let name = name(vector);
        let result = krippendorff_alpha(&reliability(vector), level(vector));
        match &vector["alpha"] {
            Value::Null => {
                assert_eq!(result.alpha, None, "{name}");
                let expected_reason = if name.contains("no_pairable") {
                    matches!(result.reason, Some(AlphaUndefined::NoPairableUnits))
                } else {
                    matches!(result.reason, Some(AlphaUndefined::NoVariation { .. }))
                };
                assert!(expected_reason, "{name}: reason {:?}", result.reason);
                undefined += 1;
            }
            expected => {
                let expected = expected.as_f64().unwrap();
                assert_close(name, result.alpha, expected, tolerance(vector));
                if let Some(exact) = vector["alpha_exact"].as_str() {
                    assert_close(name, result.alpha, exact_rational(exact), tolerance(vector));
                }
                assert!(result.reason.is_none(), "{name}");
                defined += 1;
            }
        }
    }
    println!("{defined} defined and {undefined} undefined alphas matched");
    assert_eq!(defined + undefined, vectors.len());
}

#[test]
fn json_reader_reads_every_numeric_vector() {
    let Some(vectors) = vectors() else { return };
    let mut read = 0;
    let numeric = |vector: &&Value| {
        vector["data"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|row| row.as_array().unwrap())
            .all(|cell| !cell.is_string())
    };
    for vector in vectors.iter().filter(numeric) {
        let document = serde_json::json!({ "data": vector["data"] }).to_string();
        let parsed = parse_reliability_json(&document).unwrap();
        assert_eq!(parsed, reliability(vector), "{}", name(vector));
        read += 1;
    }
    println!("{read} vectors read through the JSON reader");
    assert!(read > 0);
}

#[test]
fn canonical_intermediates_match() {
    let Some(vectors) = vectors() else { return };
    let mut checked = 0;
    for vector in vectors
        .iter()
        .filter(|vector| vector.get("intermediates").is_some())
    {
        let intermediates = &vector["intermediates"];
        let result = krippendorff_alpha(&reliability(vector), level(vector));
        assert_eq!(
            result.pairable_values as f64,
            intermediates["n"].as_f64().unwrap(),
            "{}",
            name(vector)
        );
        assert_eq!(
            result.distinct_values,
            intermediates["values"].as_array().unwrap().len()
        );
        let d_o = exact_rational(intermediates["D_o_exact"].as_str().unwrap());
        let d_e = exact_rational(intermediates["D_e_exact"].as_str().unwrap());
        assert_close(
            name(vector),
            result.observed_disagreement,
            d_o,
            1e-12 * d_o.max(1.0),
        );
        assert_close(
            name(vector),
            result.expected_disagreement,
            d_e,
            1e-12 * d_e.max(1.0),
        );
        checked += 1;
    }
    println!("{checked} sets of intermediates matched");
    assert!(checked > 0);
}

#[test]
fn pairwise_alphas_match() {
    let Some(vectors) = vectors() else { return };
    let mut checked = 0;
    for vector in vectors
        .iter()
        .filter(|vector| vector.get("pairwise_alphas_ordinal").is_some())
    {
        let pairs = pairwise_alphas(&reliability(vector), MeasurementLevel::Ordinal);
        for pair in &pairs {
            let key = format!("{}-{}", pair.coder_a, pair.coder_b);
            let expected = vector["pairwise_alphas_ordinal"][&key].as_f64().unwrap();
            assert_close(
                &format!("{} {key}", name(vector)),
                pair.result.alpha,
                expected,
                1e-12,
            );
            checked += 1;
        }
    }
    println!("{checked} pairwise alphas matched");
    assert!(checked > 0);
}

#[test]
fn fixed_index_replicates_match() {
    let Some(vectors) = vectors() else { return };
    let mut checked = 0;
    for vector in vectors.iter().filter(|vector| {
        vector["bootstrap"]
            .get("fixed_index_replicates_default_rng0_first3")
            .is_some()
    }) {
        let replicates = vector["bootstrap"]["fixed_index_replicates_default_rng0_first3"]
            .as_array()
            .unwrap();
        let draws: Vec<Vec<usize>> = replicates
            .iter()
            .map(|replicate| {
                replicate["indices"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|index| index.as_u64().unwrap() as usize)
                    .collect()
            })
            .collect();
        let prepared = PreparedAlpha::new(&reliability(vector), level(vector));
        let summary = prepared.bootstrap_replicates(&draws, 0.95).unwrap();
        for (index, replicate) in replicates.iter().enumerate() {
            let expected = replicate["alpha"].as_f64().unwrap();
            assert_close(
                &format!("{} replicate {index}", name(vector)),
                summary.replicate_alphas[index],
                expected,
                1e-12,
            );
            checked += 1;
        }
    }
    println!("{checked} fixed-index replicates matched");
    assert!(checked > 0);
}

#[test]
fn bootstrap_intervals_fall_within_the_reference_spread() {
    let Some(vectors) = vectors() else { return };
    let mut checked = 0;
    for vector in vectors.iter().filter(|vector| {
        vector["bootstrap"]
            .get("percentile_unit_bootstrap_seed_spread_200_runs")
            .is_some()
    }) {
        let name = name(vector);
        let spread = &vector["bootstrap"]["percentile_unit_bootstrap_seed_spread_200_runs"];
        let field = |key: &str| spread[key].as_f64().unwrap();
        let summary = PreparedAlpha::new(&reliability(vector), level(vector))
            .bootstrap(&BootstrapConfig::default())
            .unwrap();
        let alpha = summary.estimate.alpha.unwrap();
        let (low, high) = (summary.ci_low.unwrap(), summary.ci_high.unwrap());
        println!("{name}: alpha {alpha:.4}, 95% CI [{low:.4}, {high:.4}]");
        assert!(
            low <= alpha && alpha <= high,
            "{name}: [{low}, {high}] misses {alpha}"
        );
        assert!(
            (low - field("lo_mean")).abs() <= 5.0 * field("lo_sd") + 1e-3,
            "{name}: lower limit {low} against {} ± {}",
            field("lo_mean"),
            field("lo_sd")
        );
        assert!(
            (high - field("hi_mean")).abs() <= 5.0 * field("hi_sd") + 1e-3,
            "{name}: upper limit {high} against {} ± {}",
            field("hi_mean"),
            field("hi_sd")
        );
        let width = high - low;
        assert!(
            (width - field("width_mean")).abs() <= 5.0 * field("width_sd"),
            "{name}: width {width} against {} ± {}",
            field("width_mean"),
            field("width_sd")
        );
        assert_eq!(summary.undefined_replicates, 0, "{name}");
        checked += 1;
    }
    println!("{checked} bootstrap intervals checked against the reference spread");
    assert!(checked > 0);
}

/// The item list embedded in the permutation-example notes (`items=[…]. Encoding …`).
fn permutation_items(vector: &Value) -> Vec<Value> {
    let notes = vector["notes"].as_str().unwrap();
    let start = notes.find("items=").unwrap() + "items=".len();
    let mut stream = serde_json::Deserializer::from_str(&notes[start..]).into_iter::<Value>();
    match stream.next().unwrap().unwrap() {
        Value::Array(items) => items,
        other => panic!("{}: items are {other}", name(vector)),
    }
}

#[test]
fn ordering_encodings_reproduce_the_permutation_example() {
    let Some(vectors) = vectors() else { return };
    let examples: HashMap<&str, &Value> = vectors
        .iter()
        .filter(|vector| name(vector).starts_with("permutation_encoding_example_"))
        .map(|vector| (name(vector), vector))
        .collect();
    let Some(reference) = examples.get("permutation_encoding_example_E1_whole_answer_nominal")
    else {
        fixtures::missing("the permutation example in kalpha/vectors.json");
        return;
    };
    let items = permutation_items(reference);
    let annotators = items[0]["answers"].as_array().unwrap().len();
    let annotations = OrderingAnnotations::new(
        (0..annotators)
            .map(|index| format!("annotator-{index}"))
            .collect(),
        items
            .iter()
            .enumerate()
            .map(|(index, item)| AnnotatedOrdering {
                item_id: format!("item-{index}"),
                answers: item["answers"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|answer| {
                        Some(
                            answer
                                .as_array()
                                .unwrap()
                                .iter()
                                .map(|label| label.as_u64().unwrap() as u8)
                                .collect(),
                        )
                    })
                    .collect(),
            })
            .collect(),
    )
    .unwrap();

    let cases = [
        (
            OrderingEncoding::Answer,
            "permutation_encoding_example_E1_whole_answer_nominal",
        ),
        (
            OrderingEncoding::Position,
            "permutation_encoding_example_E3_per_position_value_ordinal",
        ),
        (
            OrderingEncoding::Rank,
            "permutation_encoding_example_E3b_per_element_rank_ordinal",
        ),
    ];
    let mut checked = 0;
    for (encoding, vector_name) in cases {
        let Some(vector) = examples.get(vector_name) else {
            panic!("{vector_name} is missing while the E1 example is present");
        };
        let encoded = annotations.encode(encoding);
        assert_eq!(encoded.level, level(vector), "{vector_name}");
        if encoding != OrderingEncoding::Answer {
            // Per-slot encodings must produce the very same table.
            assert_eq!(encoded.data, reliability(vector), "{vector_name}");
        }
        let result = krippendorff_alpha(&encoded.data, encoded.level);
        assert_close(
            vector_name,
            result.alpha,
            vector["alpha"].as_f64().unwrap(),
            1e-12,
        );
        checked += 1;
    }
    println!("{checked} ordering encodings matched");
}
