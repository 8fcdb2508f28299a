//! Where a leaderboard row came from: `run` for a model run of this hub (linked to its
//! stamp), `submitted` for an upload, and the board filtered by either.

use enact_hub::app::Hub;
use enact_hub::core::credentials::Role;
use enact_hub::core::submission::Visibility;
use enact_hub::store;
use reqwest::Method;
use serde_json::Value;

use crate::helpers::*;
use crate::runs::{answer_text, run_fixture, scripts};
use crate::server_runs::{keyed, run_to_submission};
use crate::standin::{StandIn, StandInConfig, Step};

/// The leaderboard's submission rows (Human and baselines left out), by model.
fn submission_rows(board: &Value) -> Vec<&Value> {
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .filter(|r| r["source"] == "submission" && r["baseline"] == false)
        .collect()
}

#[tokio::test]
async fn a_run_s_row_is_run_with_its_stamp_and_an_upload_s_is_submitted() {
    let (dir, pool, records) = run_fixture(1).await;
    let root = dir.path().join("release");
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&root, &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    let (_, admin) = api_token(&pool, "root", Role::Admin, None, None).await;
    let (_, submitter) = api_token(&pool, "lab", Role::Submitter, None, None).await;

    // The upload claims to be a run in every field it can: it stays `submitted`.
    let upload = submit_to(
        &server,
        "mini",
        "model=uploaded&notes=model%20run%20of%20standin-vl",
        &submitter,
        answers(&records, &[0]),
    )
    .await;
    assert_eq!(upload.status, 201, "{}", upload.text);
    let upload = upload.json();
    assert_eq!(upload["provenance"], "submitted");
    assert!(upload.get("run").is_none(), "{upload}");

    let (run, submission) = run_to_submission(&server, &hub, &admin, &standin, "asked-here").await;

    let board = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .expect(200)
        .await
        .json();
    let rows = submission_rows(&board);
    let of = |model: &str| {
        *rows
            .iter()
            .find(|r| r["model"] == model)
            .unwrap_or_else(|| panic!("no row of {model}: {board}"))
    };
    assert_eq!(of("Stand-in")["provenance"], "run");
    assert_eq!(of("Stand-in")["run"], run);
    assert_eq!(of("Stand-in")["submission"], submission);
    assert_eq!(of("uploaded")["provenance"], "submitted");
    assert!(of("uploaded").get("run").is_none());

    let filtered = |provenance: &str| {
        let server = &server;
        let path = format!("/api/v1/datasets/mini/leaderboard?provenance={provenance}");
        async move {
            let board = server.call(Method::GET, &path).expect(200).await.json();
            submission_rows(&board)
                .iter()
                .map(|r| r["model"].as_str().expect("model").to_owned())
                .collect::<Vec<_>>()
        }
    };
    assert_eq!(filtered("run").await, ["Stand-in"]);
    assert_eq!(filtered("submitted").await, ["uploaded"]);
    assert!(filtered("reported").await.is_empty());
    let refused = server
        .call(
            Method::GET,
            "/api/v1/datasets/mini/leaderboard?provenance=claimed",
        )
        .expect(400)
        .await;
    assert!(refused.text.contains("provenance"), "{}", refused.text);

    // The page's badge links a run's row to its stamp, readable by anyone while listed.
    let page = server
        .call(Method::GET, "/leaderboard/mini")
        .expect(200)
        .await;
    let stamp_path = format!("/api/v1/runs/{run}/stamp");
    assert!(page.text.contains(&stamp_path), "no link to the stamp");
    let stamp = server
        .call(Method::GET, &stamp_path)
        .expect(200)
        .await
        .json();
    assert_eq!(stamp["submission"], submission);
    assert_eq!(stamp["name"], "asked-here");
    assert_eq!(stamp["stamp"]["model"], "standin-vl");
    assert_eq!(stamp["stamp"]["endpoint_host"], {
        let url = url::Url::parse(&standin.endpoint()).expect("a URL");
        format!(
            "{}:{}",
            url.host_str().expect("a host"),
            url.port().expect("a port")
        )
    });
    assert!(
        stamp["stamp"]["prompt_hash"]
            .as_str()
            .is_some_and(|h| h.len() == 64)
    );

    // Off the leaderboard, its stamp is an admin's to read.
    let mut conn = write_tx(&pool).await;
    store::submissions::update_listing(&mut conn, submission, None, Some(Visibility::Hidden))
        .await
        .expect("hide");
    conn.commit().await.expect("commit");
    server.call(Method::GET, &stamp_path).expect(404).await;
    server
        .call(Method::GET, &stamp_path)
        .bearer(&admin)
        .expect(200)
        .await;
    server.stop().await;
}
