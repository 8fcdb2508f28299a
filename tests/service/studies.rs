//! Ablation studies end to end on the synthetic world: a baseline release and variants made
//! with `items_from` from replays rendered another way, imported with their scene graphs; a
//! study over them; submissions; and the report checked against figures computed here.

use std::collections::HashSet;
use std::path::Path;
use std::sync::{Arc, Mutex};

use enact_hub::core::credentials::Role;
use enact_hub::core::pipeline::variant::items_from;
use enact_hub::core::pipeline::{GenerateOptions, generate};
use enact_hub::core::world::{Activity, CameraRig, FrameImages, SimulateOptions, simulate};
use reqwest::Method;
use serde_json::{Value, json};
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::helpers::{Call, TestServer, api_token, enact_hub, import, options, spawn_app_with};

/// The baseline's dataset name.
pub const BASELINE: &str = "world";

fn camera(change: impl Fn(&mut CameraRig)) -> CameraRig {
    let mut rig = CameraRig {
        image_size: 96,
        ..CameraRig::default()
    };
    change(&mut rig);
    rig
}

fn replay(dir: &Path, rig: CameraRig) {
    simulate(&SimulateOptions {
        seed: 5,
        activity: Activity::MakeTea,
        length: Some(9),
        camera: rig,
    })
    .expect("simulate")
    .write_replay(dir, FrameImages::KeyFrames)
    .expect("write replay");
}

/// A server holding the world baseline (`world`, L = 3..5) and one variant dataset per
/// `(dataset, camera)`, each made with `items_from` and imported with the baseline's scene
/// graphs; and the baseline's QA records.
pub async fn world_with_variants(variants: &[(&str, CameraRig)]) -> (TestServer, Vec<Value>) {
    let variants: Vec<(String, CameraRig)> = variants
        .iter()
        .map(|(name, rig)| ((*name).to_owned(), *rig))
        .collect();
    let records = Arc::new(Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        replay(&dir.join("base-replay"), camera(|_| {}));
        let base = dir.join("base");
        generate(
            &dir.join("base-replay"),
            &base,
            &GenerateOptions {
                num_to_sample: 2,
                step_lengths: vec![3, 4, 5],
                ..GenerateOptions::default()
            },
            &|_| {},
        )
        .expect("generate the baseline");
        let mut base_options = options(BASELINE);
        base_options.scene_graphs = Some(base.join("replayed_activities"));
        import(&pool, &base, &base_options).await;
        for (name, rig) in &variants {
            let replayed = dir.join(format!("{name}-replay"));
            replay(&replayed, *rig);
            let out = dir.join(name);
            items_from(&replayed, &base, &out, &Default::default()).expect("items_from");
            // Verified like the baseline: its scene graphs, so only the images differ.
            let mut variant_options = options(name);
            variant_options.scene_graphs = Some(base.join("replayed_activities"));
            import(&pool, &out, &variant_options).await;
        }
        let qa = std::fs::read_to_string(base.join("QA/enact_ordering.jsonl")).expect("QA");
        *shared.lock().expect("lock") = qa
            .lines()
            .map(|l| serde_json::from_str(l).expect("record"))
            .collect();
    })
    .await;
    let records = records.lock().expect("lock").clone();
    (server, records)
}

/// The indices of records whose place among their direction's records, k, has `pick(k)`.
fn within_direction(records: &[Value], pick: impl Fn(usize) -> bool) -> HashSet<usize> {
    let mut seen = std::collections::HashMap::new();
    let mut chosen = HashSet::new();
    for (i, r) in records.iter().enumerate() {
        let direction = r["type"].as_str().expect("type").starts_with("forward");
        let k = seen.entry(direction).or_insert(0usize);
        if pick(*k) {
            chosen.insert(i);
        }
        *k += 1;
    }
    chosen
}

/// Compact answers: each record's ground truth, except the records in `skip` (not answered:
/// the strict policy scores them 0).
fn answers_without(records: &[Value], skip: &HashSet<usize>) -> String {
    records
        .iter()
        .enumerate()
        .filter(|(i, _)| !skip.contains(i))
        .map(|(_, r)| json!({"id": r["id"], "answer": r["gt_answer"]}).to_string() + "\n")
        .collect()
}

async fn admin(server: &TestServer) -> String {
    api_token(&server.pool, "admin", Role::Admin, None, None)
        .await
        .1
}

fn create(server: &TestServer, token: &str, body: Value) -> Call {
    server
        .call(Method::POST, "/api/v1/admin/studies")
        .bearer(token)
        .json(&body)
}

async fn submit(server: &TestServer, token: &str, dataset: &str, model: &str, body: String) {
    server
        .call(
            Method::POST,
            &format!("/api/v1/datasets/{dataset}/submissions?model={model}"),
        )
        .bearer(token)
        .body(body)
        .expect(201)
        .await;
}

fn direction_cell<'a>(report: &'a Value, variant: &str, direction: &str) -> &'a Value {
    report["cells"]
        .as_array()
        .expect("cells")
        .iter()
        .find(|c| {
            c["variant"] == variant && c["direction"] == direction && c["step_length"].is_null()
        })
        .unwrap_or_else(|| panic!("no {variant} {direction} cell in {report}"))
}

fn close(actual: &Value, expected: f64, what: &str) {
    let actual = actual
        .as_f64()
        .unwrap_or_else(|| panic!("{what}: {actual} is not a number"));
    assert!(
        (actual - expected).abs() <= 1e-9 * expected.abs().max(1.0),
        "{what}: {actual} vs {expected}"
    );
}

fn mean(xs: &[f64]) -> f64 {
    xs.iter().sum::<f64>() / xs.len() as f64
}

fn variance(xs: &[f64]) -> f64 {
    let m = mean(xs);
    xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64
}

/// C(n, k) / 2ⁿ summed for k ≤ kmax, in exact integers.
fn binomial_lower_tail(n: u64, kmax: u64) -> f64 {
    let mut c: u128 = 1;
    let mut sum: u128 = 0;
    for k in 0..=kmax {
        if k > 0 {
            c = c * u128::from(n - k + 1) / u128::from(k);
        }
        sum += c;
    }
    sum as f64 / 2f64.powi(n as i32)
}

#[tokio::test]
async fn a_study_reports_no_difference_for_the_same_answers_and_the_planted_one_exactly() {
    let (server, records) =
        world_with_variants(&[("world-fov30", camera(|r| r.fov_deg = 30.0))]).await;
    let token = admin(&server).await;
    let created = create(
        &server,
        &token,
        json!({"name": "camera", "baseline": BASELINE,
               "variants": ["Camera FOV/Aperture 30=world-fov30"]}),
    )
    .expect(201)
    .await;
    let study = created.json();
    let n = records.len();
    assert!(n >= 12, "the world gives {n} items");
    assert_eq!(study["variants"][0]["aligned"], n);
    assert_eq!(study["variants"][0]["alignment"]["by_id"], n);
    assert_eq!(
        study["variants"][0]["alignment"]["verified_differently"], 0,
        "imported with the baseline's scene graphs"
    );

    // The same answers on both datasets (a few missed, so the scores vary).
    let missed = within_direction(&records, |k| k % 4 == 1);
    for dataset in [BASELINE, "world-fov30"] {
        submit(
            &server,
            &token,
            dataset,
            "same",
            answers_without(&records, &missed),
        )
        .await;
    }
    let (status, report) = server
        .get_json("/api/v1/studies/camera/report?model=same&by_step_length=true")
        .await;
    assert_eq!(status, 200, "{report}");
    for direction in ["forward", "inverse"] {
        let cell = direction_cell(&report, "Aperture 30", direction);
        assert_eq!(cell["delta"], 0.0, "{cell}");
        assert_eq!(cell["t"], 0.0, "{cell}");
        close(&cell["p"], 1.0, "Welch p of equal samples");
        assert_eq!(cell["sign_test"]["p"], 1.0);
        assert_eq!(cell["sign_test"]["ties"], cell["n_baseline"]);
        // Every difference is 0: the paired t has no value and says why.
        assert!(cell["paired_t"]["p"].is_null());
        assert_eq!(cell["paired_t"]["reason"]["kind"], "constant_difference");
    }
    assert!(
        report["cells"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c["step_length"] == 4),
        "per step length on request"
    );
    let stamp = &report["stamp"];
    assert_eq!(stamp["baseline"]["name"], BASELINE);
    assert_eq!(stamp["baseline"]["hash"].as_str().unwrap().len(), 64);
    assert_eq!(stamp["variants"][0]["dataset"], "world-fov30");
    assert!(stamp["variants"][0]["submission"].is_i64());
    assert_eq!(stamp["hub"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(stamp["hub"]["commit"], enact_hub::core::version::COMMIT);

    // A planted difference: the baseline misses every 5th item, the variant every 3rd.
    let base_missed = within_direction(&records, |k| k % 5 == 0);
    let variant_missed = within_direction(&records, |k| k % 3 == 0);
    submit(
        &server,
        &token,
        BASELINE,
        "planted",
        answers_without(&records, &base_missed),
    )
    .await;
    submit(
        &server,
        &token,
        "world-fov30",
        "planted",
        answers_without(&records, &variant_missed),
    )
    .await;
    let (status, report) = server
        .get_json("/api/v1/studies/camera/report?model=planted")
        .await;
    assert_eq!(status, 200, "{report}");
    for direction in ["forward", "inverse"] {
        // The figures computed here: a correct answer scores 1, a missing one 0.
        let indices: Vec<usize> = (0..n)
            .filter(|&i| records[i]["type"].as_str().unwrap().starts_with(direction))
            .collect();
        let score = |missed: &HashSet<usize>, i: usize| f64::from(u8::from(!missed.contains(&i)));
        let b: Vec<f64> = indices.iter().map(|&i| score(&base_missed, i)).collect();
        let v: Vec<f64> = indices.iter().map(|&i| score(&variant_missed, i)).collect();
        let (sb, sv) = (variance(&b) / b.len() as f64, variance(&v) / v.len() as f64);
        let t = (mean(&v) - mean(&b)) / (sb + sv).sqrt();
        let df = (sb + sv).powi(2)
            / (sb.powi(2) / (b.len() - 1) as f64 + sv.powi(2) / (v.len() - 1) as f64);
        let p = 2.0 * StudentsT::new(0.0, 1.0, df).unwrap().sf(t.abs());
        let cell = direction_cell(&report, "Aperture 30", direction);
        close(&cell["delta"], mean(&v) - mean(&b), "Δ");
        close(&cell["t"], t, "Welch t");
        close(&cell["df"], df, "Welch df");
        close(&cell["p"], p, "Welch p");
        assert_eq!(cell["n_baseline"], b.len());

        let d: Vec<f64> = v.iter().zip(&b).map(|(v, b)| v - b).collect();
        let paired_t = mean(&d) / (variance(&d) / d.len() as f64).sqrt();
        let paired_p = 2.0
            * StudentsT::new(0.0, 1.0, (d.len() - 1) as f64)
                .unwrap()
                .sf(paired_t.abs());
        close(&cell["paired_t"]["t"], paired_t, "paired t");
        close(&cell["paired_t"]["p"], paired_p, "paired p");
        let up = d.iter().filter(|x| **x > 0.0).count() as u64;
        let down = d.iter().filter(|x| **x < 0.0).count() as u64;
        assert_eq!(cell["sign_test"]["positive"], up);
        assert_eq!(cell["sign_test"]["negative"], down);
        let sign_p = (2.0 * binomial_lower_tail(up + down, up.min(down))).min(1.0);
        close(&cell["sign_test"]["p"], sign_p, "sign p");
    }

    // The other representations, each stamped with the datasets' hashes.
    let hash = report["stamp"]["baseline"]["hash"]
        .as_str()
        .unwrap()
        .to_owned();
    for format in ["csv", "tex", "svg", "handedness-svg"] {
        let response = server
            .get(&format!(
                "/api/v1/studies/camera/report?model=planted&format={format}"
            ))
            .await;
        assert_eq!(response.status(), 200, "{format}");
        let text = response.text().await.unwrap();
        assert!(text.contains(&hash), "{format} is stamped");
    }
    let svg = server
        .get("/api/v1/studies/camera/report?model=planted&format=svg")
        .await
        .text()
        .await
        .unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Camera FOV") && svg.contains("Aperture 30"));

    // The command line writes the same report's files.
    let out = tempfile::tempdir().unwrap();
    let run = enact_hub()
        .args(["study", "report", "camera", "--model", "planted", "--db"])
        .arg(server.db_path())
        .arg("--out")
        .arg(out.path())
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let written: Value =
        serde_json::from_slice(&std::fs::read(out.path().join("study.json")).expect("study.json"))
            .unwrap();
    assert_eq!(written["cells"], report["cells"]);
    for file in [
        "cells.csv",
        "cells.tex",
        "table.csv",
        "table.tex",
        "heatmap.svg",
        "handedness.csv",
        "handedness.svg",
    ] {
        let text = std::fs::read_to_string(out.path().join(file)).expect(file);
        assert!(text.contains(&hash), "{file} is stamped");
    }
    server.stop().await;
}

#[tokio::test]
async fn studies_refuse_what_cannot_be_compared_and_are_audited() {
    let (server, records) =
        world_with_variants(&[("world-fov30", camera(|r| r.fov_deg = 30.0))]).await;
    let token = admin(&server).await;
    // A dataset with other items: nothing aligns.
    let other = tempfile::tempdir().unwrap();
    crate::helpers::write_release(other.path(), &[3]);
    {
        let pool = server.pool.clone();
        import(&pool, other.path(), &options("other")).await;
    }
    let refusal = |body: Value, status: u16, needle: &'static str| {
        let server = &server;
        let token = token.clone();
        async move {
            let reply = create(server, &token, body).expect(status).await;
            assert!(reply.error().contains(needle), "{}", reply.error());
            reply.json()
        }
    };
    refusal(
        json!({"name": "s", "baseline": BASELINE, "variants": ["Camera=world-fov30"]}),
        400,
        "variants[0]",
    )
    .await;
    // A malformed variant is told what a variant is, and which one it was.
    for (variant, needle) in [
        (
            json!({"family": "Camera", "label": "30"}),
            "missing field `dataset`",
        ),
        (json!(42), "a variant is \"FAMILY/LABEL=DATASET\""),
    ] {
        let reply = create(
            &server,
            &token,
            json!({"name": "s", "baseline": BASELINE, "variants": ["Camera/20=world-fov30", variant]}),
        )
        .expect(422)
        .await;
        let error = reply.error();
        assert!(
            error.contains("variants[1]") && error.contains(needle),
            "{error}"
        );
    }
    let missing = refusal(
        json!({"name": "s", "baseline": BASELINE, "variants": ["Camera/30=nope"]}),
        400,
        "no dataset named 'nope'",
    )
    .await;
    assert_eq!(missing["code"], "study_variant_missing");
    assert_eq!(missing["details"]["variant"], "Camera/30");
    let baseline_missing = refusal(
        json!({"name": "s", "baseline": "nope", "variants": ["Camera/30=world-fov30"]}),
        400,
        "baseline: no dataset named 'nope'",
    )
    .await;
    assert_eq!(baseline_missing["code"], "study_baseline_missing");
    let unaligned = refusal(
        json!({"name": "s", "baseline": BASELINE, "variants": ["Camera/30=other"]}),
        400,
        "none of dataset 'other'",
    )
    .await;
    assert_eq!(unaligned["code"], "study_variant_unaligned");
    assert_eq!(unaligned["details"]["baseline"], BASELINE);
    refusal(
        json!({"name": "bad name", "baseline": BASELINE, "variants": ["Camera/30=world-fov30"]}),
        400,
        "not allowed",
    )
    .await;
    let body = json!({"name": "cam", "baseline": BASELINE,
                      "variants": [{"family": "Camera", "label": "30", "dataset": "world-fov30"}]});
    let submitter = api_token(&server.pool, "team", Role::Submitter, None, None)
        .await
        .1;
    create(&server, &submitter, body.clone()).expect(403).await;
    create(&server, &token, body.clone()).expect(201).await;
    let exists = refusal(body, 409, "exists already").await;
    assert_eq!(exists["code"], "study_exists");
    assert_eq!(exists["details"]["study"], "cam");

    // The variant imported with its own replay's scene graphs: a 30° camera sees less, so some
    // items are judged by other signatures, and the study says so.
    let dir = server.dir().to_path_buf();
    let mut own = options("world-own");
    own.scene_graphs = Some(dir.join("world-fov30-replay"));
    import(&server.pool, &dir.join("world-fov30"), &own).await;
    let judged = create(
        &server,
        &token,
        json!({"name": "own", "baseline": BASELINE, "variants": ["Camera/own=world-own"]}),
    )
    .expect(201)
    .await
    .json();
    let differently = judged["variants"][0]["alignment"]["verified_differently"]
        .as_u64()
        .expect("count");
    assert!(differently > 0, "{judged}");
    let page = server.get("/studies/own").await.text().await.unwrap();
    assert!(
        page.contains("judged by other rules than the baseline"),
        "{page}"
    );

    // Reports name what is missing.
    let (status, missing) = server.get_json("/api/v1/studies/cam/report").await;
    assert_eq!(status, 400);
    assert_eq!(missing["code"], "exactly_one_of", "{missing}");
    assert_eq!(missing["details"]["fields"], "model, human", "{missing}");
    let (status, nobody) = server
        .get_json("/api/v1/studies/cam/report?model=ghost")
        .await;
    assert_eq!(status, 404);
    assert!(
        nobody["error"]
            .as_str()
            .unwrap()
            .contains("no published submission of model 'ghost'")
    );
    submit(
        &server,
        &token,
        BASELINE,
        "half",
        answers_without(&records, &HashSet::new()),
    )
    .await;
    let (status, half) = server
        .get_json("/api/v1/studies/cam/report?model=half")
        .await;
    assert_eq!(status, 200);
    assert!(
        half["variants"][0]["missing"]
            .as_str()
            .unwrap()
            .contains("world-fov30")
    );
    let (status, human) = server
        .get_json("/api/v1/studies/cam/report?human=true")
        .await;
    assert_eq!(status, 404, "{human}");

    // Listed, shown on the pages, audited, deleted.
    let (_, list) = server.get_json("/api/v1/studies").await;
    assert_eq!(list[0]["name"], "cam");
    assert_eq!(list[1]["name"], "own");
    let page = server.get("/studies/cam?row=model:half").await;
    assert_eq!(page.status(), 200);
    let html = page.text().await.unwrap();
    assert!(html.contains("class=\"study-heatmap\"") && html.contains("no published submission"));
    // The alignment table is filled from the report's own alignment.
    assert!(!html.contains("not computed"), "{html}");
    let audit = enact_hub()
        .args(["audit", "--action", "study", "--json", "--db"])
        .arg(server.db_path())
        .output()
        .unwrap();
    let entries: Value = serde_json::from_slice(&audit.stdout).unwrap();
    assert_eq!(entries[0]["action"], "study.create");
    // Newest first: the study `own`, with its baseline, variant and alignment.
    assert_eq!(entries[0]["target"], "study own");
    assert_eq!(entries[0]["dataset"], BASELINE);
    assert_eq!(
        entries[0]["detail"],
        format!(
            "baseline {BASELINE}; Camera/own=world-own ({} aligned)",
            records.len()
        )
    );
    assert_eq!(entries[1]["target"], "study cam");
    server
        .call(Method::DELETE, "/api/v1/admin/studies/cam")
        .bearer(&token)
        .expect(204)
        .await;
    let (status, _) = server.get_json("/api/v1/studies/cam").await;
    assert_eq!(status, 404);
    let audit = enact_hub()
        .args(["audit", "--action", "study.delete", "--json", "--db"])
        .arg(server.db_path())
        .output()
        .unwrap();
    let deleted: Value = serde_json::from_slice(&audit.stdout).unwrap();
    assert_eq!(deleted[0]["target"], "study cam");
    assert_eq!(deleted[0]["actor"], "admin");
    // Deleting it again names what is missing.
    let again = server
        .call(Method::DELETE, "/api/v1/admin/studies/cam")
        .bearer(&token)
        .expect(404)
        .await;
    assert!(again.error().contains("no study named 'cam'"));
    server.stop().await;
}

/// The Human row as the compared "model": an annotator answers every item of the baseline
/// right and reverses some on the variant; the report is the annotators' and can only fall.
#[tokio::test]
async fn the_human_row_is_reported_like_a_model() {
    use enact_hub::app::Hub;
    use enact_hub::core::annotation::{Draft, InteractionCounts, Session};

    let (server, records) =
        world_with_variants(&[("world-fov30", camera(|r| r.fov_deg = 30.0))]).await;
    let token = admin(&server).await;
    create(
        &server,
        &token,
        json!({"name": "camera", "baseline": BASELINE,
               "variants": ["Camera FOV/Aperture 30=world-fov30"]}),
    )
    .expect(201)
    .await;
    let hub = Hub::from(server.pool.clone());
    let ann = crate::annotate::annotator(&server, "ann", false).await;
    let session = Session {
        annotator: ann,
        name: "ann".to_owned(),
        is_admin: false,
        csrf_token: String::new(),
    };
    let ids: Vec<&str> = records
        .iter()
        .map(|r| r["id"].as_str().expect("id"))
        .collect();
    let reversed = within_direction(&records, |k| k % 3 == 0);
    for dataset in [BASELINE, "world-fov30"] {
        crate::annotate::assign_in(&server, dataset, ann, &ids).await;
        for (i, record) in records.iter().enumerate() {
            let mut slots: Vec<Option<u8>> = record["gt_answer"]
                .as_array()
                .expect("gt")
                .iter()
                .map(|l| Some(l.as_u64().expect("label") as u8))
                .collect();
            if dataset != BASELINE && reversed.contains(&i) {
                slots.reverse();
            }
            let draft = Draft {
                slots,
                counts: InteractionCounts::default(),
                history: Vec::new(),
            };
            enact_hub::app::annotation::answer(&hub, &session, dataset, ids[i], &draft)
                .await
                .expect("answered");
        }
    }
    let (status, report) = server
        .get_json("/api/v1/studies/camera/report?human=true")
        .await;
    assert_eq!(status, 200, "{report}");
    assert_eq!(report["stamp"]["row"], "Human");
    assert!(report["stamp"]["baseline_submission"].is_null());
    for direction in ["forward", "inverse"] {
        let cell = direction_cell(&report, "Aperture 30", direction);
        assert_eq!(cell["mean_baseline"], 1.0, "{cell}");
        assert!(cell["delta"].as_f64().expect("delta") < 0.0, "{cell}");
        assert_eq!(cell["sign_test"]["positive"], 0, "{cell}");
        assert!(cell["sign_test"]["negative"].as_u64() > Some(0), "{cell}");
    }
    let handedness = report["handedness"].as_array().expect("handedness");
    assert_eq!(
        handedness.len(),
        4,
        "baseline and variant, two directions each"
    );
    let (status, both) = server
        .get_json("/api/v1/studies/camera/report?human=true&model=m")
        .await;
    assert_eq!(status, 400);
    assert_eq!(both["error"], "give exactly one of model, human", "{both}");
    server.stop().await;
}

#[tokio::test]
async fn a_stratified_subset_keeps_the_sources_items_and_pairs_with_it() {
    let (server, records) = world_with_variants(&[]).await;
    // The source's strata, counted here.
    let mut available: std::collections::BTreeMap<(String, usize), usize> = Default::default();
    for r in &records {
        let direction = r["type"]
            .as_str()
            .expect("type")
            .split('_')
            .next()
            .expect("d");
        let l = r["key_frame_ids"].as_array().expect("frames").len();
        *available.entry((direction.to_owned(), l)).or_default() += 1;
    }
    let smallest = *available.values().min().expect("strata");
    assert!(smallest >= 2, "{available:?}");
    let subset = |into: &str, size: usize, allocation: &str| {
        enact_hub()
            .args(["dataset", "subset", BASELINE, "--db"])
            .arg(server.db_path())
            .args(["--into", into, "--size", &size.to_string()])
            .args(["--stratify", "direction,step_length", "--seed", "3"])
            .args(["--allocation", allocation, "--json"])
            .output()
            .expect("run")
    };
    // Equal allocation: `smallest` items of every stratum.
    let size = smallest * available.len();
    let run = subset("world-equal", size, "equal");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&run.stdout).expect("json");
    assert_eq!(report["items"], size);
    let strata = report["strata"].as_array().expect("strata");
    assert_eq!(strata.len(), available.len());
    for s in strata {
        let key = (
            s["stratum"][0].as_str().expect("direction").to_owned(),
            s["stratum"][1]
                .as_str()
                .expect("L")
                .parse::<usize>()
                .expect("L"),
        );
        assert_eq!(s["available"], available[&key], "{key:?}");
        assert_eq!(s["chosen"], smallest, "{key:?}");
    }
    // Proportional allocation: each stratum within one item of its exact share.
    let size = records.len() / 2;
    let run = subset("world-half", size, "proportional");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&run.stdout).expect("json");
    let mut total = 0;
    for s in report["strata"].as_array().expect("strata") {
        let (a, c) = (
            s["available"].as_u64().expect("n") as f64,
            s["chosen"].as_u64().expect("n") as f64,
        );
        let exact = a * size as f64 / records.len() as f64;
        assert!((c - exact).abs() < 1.0, "{s}");
        total += c as usize;
    }
    assert_eq!(total, size);

    // A variant in the studies' sense: every subset item pairs with the source's by id and is
    // judged by the same rules.
    let token = admin(&server).await;
    create(
        &server,
        &token,
        json!({"name": "subset", "baseline": "world-equal",
               "variants": [format!("Full/all items={BASELINE}")]}),
    )
    .expect(201)
    .await;
    let shown = enact_hub()
        .args(["study", "show", "subset", "--json", "--db"])
        .arg(server.db_path())
        .output()
        .expect("run");
    assert!(
        shown.status.success(),
        "{}",
        String::from_utf8_lossy(&shown.stderr)
    );
    let view: Value = serde_json::from_slice(&shown.stdout).expect("json");
    let alignment = &view["variants"][0]["alignment"];
    assert_eq!(view["baseline_items"], smallest * available.len());
    assert_eq!(alignment["by_id"], smallest * available.len());
    assert_eq!(alignment["baseline_unaligned"], 0);
    assert_eq!(alignment["verified_differently"], 0);

    // Refused before anything is written: a name in use, a size the source cannot give.
    let again = subset("world-equal", 2, "proportional");
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("exists already"));
    let too_many = subset("world-big", records.len() + 1, "proportional");
    assert!(!too_many.status.success());
    assert!(String::from_utf8_lossy(&too_many.stderr).contains("larger than the source"));
    server.stop().await;
}
