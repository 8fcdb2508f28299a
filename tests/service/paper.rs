//! `enact-hub paper`: the paper's tables regenerated from a dataset holding the paper's published
//! results and a scored submission of this hub.

use std::path::Path;

use enact_hub::core::credentials::Role;
use enact_hub::core::paper::mark::mark;
use enact_hub::core::paper::{
    CellKey, ENACT_PAPER_MAIN_TABLE_MODELS, Metric, PaperTable, enact_paper_results, table_of,
};
use reqwest::Method;
use serde_json::Value;

use crate::helpers::*;

fn run(args: &[&str], db: &Path) -> std::process::Output {
    enact_hub()
        .args(args)
        .arg("--db")
        .arg(db)
        .output()
        .expect("enact-hub runs")
}

fn succeeded(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn table(dir: &Path, name: &str) -> PaperTable {
    let text = std::fs::read_to_string(dir.join(name)).expect(name);
    PaperTable::from_json(&text).expect("the JSON table reads back")
}

/// The paper's own table of `metric`, marked by the rule.
fn published(metric: Metric) -> PaperTable {
    let mut table = table_of(metric, &enact_paper_results());
    mark(&mut table);
    table
}

/// A leaderboard row's figure at `key`, in percent as printed.
fn board_percent(row: &Value, key: CellKey, field: &str) -> Option<f64> {
    let direction = key.direction.as_str();
    row[direction]["per_step"]
        .as_array()
        .expect("per_step")
        .iter()
        .find(|cell| cell[0] == u64::from(key.step_length.get()))
        .and_then(|cell| cell[1][field].as_f64())
        .map(|v| (v * 10_000.0).round() / 100.0)
}

#[tokio::test]
async fn the_papers_tables_come_back_with_a_submissions_row_in_its_own_category() {
    let (server, records) = spawn_app_with_release().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let reply = submit_to(
        &server,
        "mini",
        "model=GPT-5",
        &alice,
        answers(&records, &[0, 3]),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let submission = reply.id();
    let db = server.db_path();
    succeeded(&run(
        &["reported", "import", "--paper", "--dataset", "mini"],
        &db,
    ));

    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("paper");
    let written = run(
        &[
            "paper",
            "--dataset",
            "mini",
            "--compare-reported",
            "--out",
            dir.to_str().unwrap(),
        ],
        &db,
    );
    succeeded(&written);
    for name in [
        "task_accuracy.tex",
        "task_accuracy_standalone.tex",
        "task_accuracy.csv",
        "task_accuracy.md",
        "pairwise_accuracy.tex",
        "pairwise_accuracy_standalone.tex",
        "pairwise_accuracy.csv",
        "pairwise_accuracy.md",
        "reproduction.csv",
        "error_analysis.svg",
        "error_analysis.png",
    ] {
        assert!(dir.join(name).is_file(), "{name} is written");
    }
    // The error-analysis figure is of the hub's rows only: the submission's, not the paper's.
    let errors = std::fs::read_to_string(dir.join("error_analysis.svg")).unwrap();
    assert!(errors.contains("<title>GPT-5</title>"), "{errors}");
    assert!(!errors.contains("Gemini 2.5 Pro"));
    assert!(
        std::fs::read(dir.join("error_analysis.png"))
            .unwrap()
            .starts_with(b"\x89PNG")
    );

    let board = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .expect(200)
        .await
        .json();
    let board_row = board["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["submission"] == submission)
        .expect("the submission's leaderboard row")
        .clone();
    for (metric, field) in [
        (Metric::TaskAccuracy, "task_accuracy"),
        (Metric::PairwiseAccuracy, "pairwise_accuracy"),
    ] {
        let name = format!("{}.json", metric.as_str());
        let table = table(&dir, &name);
        // The paper's rows, values and marks, unchanged by the hub's row beside them.
        let paper_rows: Vec<_> = table
            .rows
            .iter()
            .filter(|r| !r.source.starts_with("enact-hub"))
            .cloned()
            .collect();
        assert_eq!(paper_rows, published(metric).rows, "{name}");
        // The submission's row, in the hub's own category, with the leaderboard's figures.
        let ours = table
            .rows
            .iter()
            .find(|r| r.source == format!("enact-hub submission {submission}"))
            .expect("the submission's row");
        assert_eq!(ours.model, "GPT-5");
        assert_eq!(ours.category.as_str(), "enact-hub");
        for key in CellKey::all() {
            assert_eq!(
                ours.value(key),
                board_percent(&board_row, key, field),
                "{name} {key}"
            );
        }
        // Humans last.
        assert_eq!(table.rows.last().unwrap().model, "Human Performance");
    }

    let provenance: Value =
        serde_json::from_slice(&std::fs::read(dir.join("provenance.json")).unwrap()).unwrap();
    let cells = provenance["cells"].as_array().unwrap();
    let ours: Vec<&Value> = cells
        .iter()
        .filter(|c| c["from"]["kind"] == "submission")
        .collect();
    assert!(!ours.is_empty());
    assert!(ours.iter().all(|c| c["from"]["submission"] == submission
        && c["model"] == "GPT-5"
        && c["from"]["metric_version"].is_u64()
        && c["from"]["hub_version"].is_string()));
    assert!(cells.iter().any(|c| {
        c["from"]["kind"] == "reported"
            && c["from"]["source"]
                .as_str()
                .unwrap()
                .contains("tab:app_task_acc")
    }));

    // The reproduction check pairs the paper's GPT-5 with the hub's, cell by cell.
    let reproduction = std::fs::read_to_string(dir.join("reproduction.csv")).unwrap();
    let lines: Vec<&str> = reproduction.lines().skip(1).collect();
    assert!(!lines.is_empty());
    assert!(
        lines
            .iter()
            .all(|l| l.starts_with("GPT-5,") && l.contains(&format!(",{submission},"))),
        "{reproduction}"
    );
    let stdout = String::from_utf8_lossy(&written.stdout);
    let gpt5 = enact_paper_results()
        .into_iter()
        .find(|m| m.model == "GPT-5")
        .unwrap();
    let f3 = CellKey::parse("forward_3").unwrap();
    let expected = format!(
        "GPT-5 task_accuracy forward_3: reported {:.2}, hub ",
        gpt5.task_accuracy[&f3]
    );
    assert!(stdout.contains(&expected), "{stdout}");

    // The main-text table: the rows named, in that order.
    let main = out.path().join("main");
    let models = ENACT_PAPER_MAIN_TABLE_MODELS.join(",");
    succeeded(&run(
        &[
            "paper",
            "--dataset",
            "mini",
            "--metric",
            "pa",
            "--models",
            &models,
            "--out",
            main.to_str().unwrap(),
        ],
        &db,
    ));
    assert!(!main.join("task_accuracy.json").exists());
    let table = table(&main, "pairwise_accuracy.json");
    let names: Vec<&str> = table
        .rows
        .iter()
        .filter(|r| !r.source.starts_with("enact-hub"))
        .map(|r| r.model.as_str())
        .collect();
    assert_eq!(names, ENACT_PAPER_MAIN_TABLE_MODELS);

    // A name no row has is refused, saying which.
    let refused = run(
        &[
            "paper",
            "--dataset",
            "mini",
            "--models",
            "GPT-5,GPT-6",
            "--out",
            out.path().join("refused").to_str().unwrap(),
        ],
        &db,
    );
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("no row is named 'GPT-6'"), "{stderr}");
    assert!(!out.path().join("refused").exists());

    // Without a hub row among the chosen ones, there is no error-analysis figure.
    let published_only = out.path().join("published_only");
    succeeded(&run(
        &[
            "paper",
            "--dataset",
            "mini",
            "--models",
            "Gemini 2.5 Pro",
            "--out",
            published_only.to_str().unwrap(),
        ],
        &db,
    ));
    assert!(published_only.join("task_accuracy.json").is_file());
    assert!(!published_only.join("error_analysis.svg").exists());
    assert!(!published_only.join("error_analysis.png").exists());
    server.stop().await;
}

#[tokio::test]
async fn the_paper_page_shows_the_tables_in_both_languages_and_downloads_the_folder() {
    let (server, records) = spawn_app_with_release().await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    let reply = submit_to(
        &server,
        "mini",
        "model=GPT-5",
        &alice,
        answers(&records, &[1]),
    )
    .await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let submission = reply.id();
    succeeded(&run(
        &["reported", "import", "--paper", "--dataset", "mini"],
        &server.db_path(),
    ));

    let english = server
        .call(Method::GET, "/datasets/mini/paper?intervals=1")
        .header("accept-language", "en")
        .expect(200)
        .await
        .text;
    assert!(english.contains("Pairwise accuracy") && english.contains("Proprietary models"));
    assert!(english.contains("Gemini 2.5 Pro") && english.contains("Human Performance"));
    assert!(english.contains(&format!("enact-hub submission {submission}")));
    assert!(english.contains("paper-mark-first") && english.contains("paper-mark-second"));
    assert!(english.contains("Reproduction check"));
    // The figures and the download keep the page's choices.
    assert!(
        english.contains("/datasets/mini/paper/files/task_accuracy_by_step_length.svg?intervals=1")
    );
    assert!(english.contains("/datasets/mini/paper.tar?intervals=1"));
    assert!(english.contains("/datasets/mini/paper/files/error_analysis.svg?intervals=1"));
    assert!(english.contains("/datasets/mini/paper/files/error_analysis.png?intervals=1"));
    let without_hub_rows = server
        .call(
            Method::GET,
            "/datasets/mini/paper?models=Gemini%202.5%20Pro",
        )
        .header("accept-language", "en")
        .expect(200)
        .await
        .text;
    assert!(without_hub_rows.contains("there is no error-analysis figure"));
    assert!(!without_hub_rows.contains("files/error_analysis.svg"));

    let chinese = server
        .call(Method::GET, "/datasets/mini/paper?metric=pa")
        .header("accept-language", "zh-CN")
        .expect(200)
        .await
        .text;
    assert!(
        chinese.contains("成对准确率") && chinese.contains("闭源模型"),
        "{chinese}"
    );
    assert!(!chinese.contains("id=\"paper-task_accuracy\""));

    let svg = server
        .get("/datasets/mini/paper/files/pairwise_accuracy_by_step_length.svg")
        .await;
    assert_eq!(svg.headers()["content-type"], "image/svg+xml");
    assert!(svg.text().await.unwrap().contains("Gemini 2.5 Pro"));
    let tar = server.get("/datasets/mini/paper.tar").await;
    assert_eq!(tar.status(), 200);
    assert_eq!(tar.headers()["content-type"], "application/x-tar");
    let bytes = tar.bytes().await.unwrap();
    let mut names = Vec::new();
    let mut archive = tar::Archive::new(bytes.as_ref());
    for entry in archive.entries().unwrap() {
        names.push(entry.unwrap().path().unwrap().display().to_string());
    }
    for name in [
        "provenance.json",
        "task_accuracy.tex",
        "pairwise_accuracy_by_step_length.png",
        "error_analysis.svg",
        "error_analysis.png",
        "reproduction.csv",
    ] {
        assert!(
            names
                .iter()
                .any(|n| n == &format!("enact-hub-paper-mini/{name}")),
            "{name} in {names:?}"
        );
    }

    // Bad choices say what was wrong.
    let refused = server
        .call(Method::GET, "/datasets/mini/paper?metric=xx")
        .send()
        .await;
    assert_eq!(refused.status, 400);
    assert!(refused.text.contains("metric"), "{}", refused.text);
    let missing = server
        .call(Method::GET, "/datasets/mini/paper/files/secrets.txt")
        .send()
        .await;
    assert_eq!(missing.status, 404);
    assert!(
        missing.text.contains("no file 'secrets.txt'"),
        "{}",
        missing.text
    );
    let unknown = server
        .call(Method::GET, "/datasets/mini/paper?models=GPT-6")
        .send()
        .await;
    assert_eq!(unknown.status, 400);
    assert!(
        unknown.text.contains("no row is named") && unknown.text.contains("GPT-6"),
        "{}",
        unknown.text
    );
    server.stop().await;
}

/// A study whose baseline is the dataset puts its heat map in the folder and on the page,
/// reported for the chosen submission (there is no Human row); the error-analysis figure is
/// of that submission.
#[tokio::test]
async fn the_folder_holds_the_datasets_study_heat_maps_and_the_error_analysis_figure() {
    use enact_hub::core::world::CameraRig;

    use crate::studies::{BASELINE, world_with_variants};

    let rig = CameraRig {
        image_size: 96,
        fov_deg: 30.0,
        ..CameraRig::default()
    };
    let (server, records) = world_with_variants(&[("world-fov30", rig)]).await;
    let (_, admin) = api_token(&server.pool, "admin", Role::Admin, None, None).await;
    let (_, alice) = api_token(&server.pool, "alice", Role::Submitter, None, None).await;
    server
        .call(Method::POST, "/api/v1/admin/studies")
        .bearer(&admin)
        .json(&serde_json::json!({"name": "camera", "baseline": BASELINE,
               "variants": ["Camera FOV/Aperture 30=world-fov30"]}))
        .expect(201)
        .await;
    // Every other item answered right, so the model makes errors to analyse.
    let body: String = records
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 2 == 0)
        .map(|(_, r)| {
            serde_json::json!({"id": r["id"], "answer": r["gt_answer"]}).to_string() + "\n"
        })
        .collect();
    for dataset in [BASELINE, "world-fov30"] {
        server
            .call(
                Method::POST,
                &format!("/api/v1/datasets/{dataset}/submissions?model=m"),
            )
            .bearer(&alice)
            .body(body.clone())
            .expect(201)
            .await;
    }

    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("paper");
    succeeded(&run(
        &[
            "paper",
            "--dataset",
            BASELINE,
            "--out",
            dir.to_str().unwrap(),
        ],
        &server.db_path(),
    ));
    for name in [
        "error_analysis.svg",
        "error_analysis.png",
        "study-camera-heatmap.svg",
        "study-camera-heatmap.png",
    ] {
        assert!(dir.join(name).is_file(), "{name} is written");
    }
    let heatmap = std::fs::read_to_string(dir.join("study-camera-heatmap.svg")).unwrap();
    assert!(
        heatmap.contains("study-heatmap") && heatmap.contains("Aperture 30"),
        "{heatmap}"
    );
    // Reported for the submission's model of its account.
    assert!(
        heatmap.contains("m (alice): Δ mean pairwise accuracy"),
        "{heatmap}"
    );
    assert!(
        std::fs::read(dir.join("study-camera-heatmap.png"))
            .unwrap()
            .starts_with(b"\x89PNG")
    );
    let errors = std::fs::read_to_string(dir.join("error_analysis.svg")).unwrap();
    assert!(errors.contains("<title>m</title>"), "{errors}");

    let page = server
        .call(Method::GET, &format!("/datasets/{BASELINE}/paper"))
        .header("accept-language", "en")
        .expect(200)
        .await
        .text;
    assert!(page.contains("Studies of this dataset"), "{page}");
    assert!(page.contains(&format!(
        "/datasets/{BASELINE}/paper/files/study-camera-heatmap.png"
    )));
    let png = server
        .get(&format!(
            "/datasets/{BASELINE}/paper/files/study-camera-heatmap.png"
        ))
        .await;
    assert_eq!(png.status(), 200);
    assert_eq!(png.headers()["content-type"], "image/png");
    server.stop().await;
}
