//! The annotation UI in a real browser: headless Chromium driven by playwright-core
//! (tests/browser/annotate.mjs) against a server on 127.0.0.1:0. The stored answers and
//! telemetry are then checked here, in the database.

use std::path::{Path, PathBuf};

use enact_hub::core::credentials::{random_token as new_token, token_hash};
use enact_hub::store;
use serde_json::{Value, json};

use crate::annotate::assign;
use crate::helpers::*;

pub(crate) const CHROMIUM: &str = "/usr/bin/chromium";

fn browser_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser")
}

/// Whether Chromium and playwright-core are here (they must be in CI; elsewhere the test skips).
pub(crate) fn browser_available() -> bool {
    if !Path::new(CHROMIUM).exists() {
        assert!(
            !crate::fixtures::must_not_skip(),
            "{CHROMIUM} is missing in CI: scripts/test.sh installs it"
        );
        eprintln!("skipping: {CHROMIUM} is absent (install chromium, or run scripts/test.sh)");
        return false;
    }
    assert!(
        browser_dir().join("node_modules/playwright-core").is_dir(),
        "tests/browser/node_modules is missing: run `npm ci` in tests/browser (scripts/test.sh does)"
    );
    true
}

/// Runs `script` in tests/browser with `params`; its last line of output as JSON.
pub(crate) async fn run_node(script: &'static str, params: Value) -> Value {
    let output = tokio::task::spawn_blocking(move || {
        std::process::Command::new("node")
            .arg(browser_dir().join(script))
            .arg(params.to_string())
            .output()
            .expect("run node")
    })
    .await
    .expect("join");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "{script} failed:\n{stderr}\n{stdout}"
    );
    serde_json::from_str(stdout.lines().last().expect("a result line")).expect("JSON result")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_board_of_a_thousand_submissions_reads_at_1280_px() {
    if !browser_available() {
        return;
    }
    let (server, records) = spawn_app_with_release().await;
    crate::leaderboard::crowded_board(&server, &records, 1000, 50).await;
    // A baseline too: shown on every page, within the page's rows.
    db!(
        server.pool,
        execute,
        sqlx::query(
            "UPDATE submissions SET baseline = $1 WHERE id = (SELECT min(id) FROM submissions)"
        )
        .bind(true)
    )
    .expect("mark a baseline");
    let found = run_node(
        "leaderboard.mjs",
        json!({
            "url": server.url("/leaderboard/mini"),
            "chromium": CHROMIUM,
            "also": ["/leaderboard/mini/errors", "/", "/datasets/mini", "/api/docs", "/login"],
        }),
    )
    .await;
    // Six pages, and not one console error (CSP refusals and missing files included).
    assert_eq!(found["pages_without_console_errors"], 6, "{found}");
    assert_eq!(found["table_rows"], 50, "{found}");
    for lines in found["lines_per_panel"].as_array().expect("panels") {
        assert!(lines.as_u64().expect("lines") <= 12, "{found}");
    }
    assert!(
        found["scroll_width"].as_u64() <= found["client_width"].as_u64(),
        "the page scrolls sideways: {found}"
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn annotator_completes_a_forward_and_an_inverse_item_in_chromium() {
    if !browser_available() {
        return;
    }
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    // ENACT's own sample items (real 512x512 frames), when the shared fixtures are here.
    let sample = shared_fixtures().map(|f| f.join("enact-sample"));
    let sample_dir = sample.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let written = write_release(&root, &[3, 4, 10]);
        import(&pool, &root, &options("mini")).await;
        if let Some(sample) = sample_dir {
            import(&pool, &sample, &options("sample")).await;
        }
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records: Vec<Value> = records.lock().expect("lock").clone();
    let id = |i: usize| records[i]["id"].as_str().expect("id").to_owned();
    // write_release: forward then inverse for each L; so 0 = forward 3, 3 = inverse 4.
    let (forward, inverse, wide) = (id(0), id(3), [id(4), id(5)]);
    let token = new_token();
    let annotator = {
        let mut tx = write_tx(&server.pool).await;
        let id = store::annotations::create_annotator(&mut tx, "eve", false, &token_hash(&token))
            .await
            .expect("insert");
        tx.commit().await.expect("commit");
        id
    };
    assign(
        &server,
        annotator,
        &[&forward, &inverse, &wide[0], &wide[1]],
    )
    .await;
    // Forward L = 3, inverse L = 5 and forward L = 10 of the sample.
    let mut sample_items = Vec::new();
    if let Some(sample) = &sample {
        let qa = std::fs::read_to_string(sample.join("QA/enact_ordering.jsonl")).expect("qa");
        for (direction, steps) in [("forward", 3), ("inverse", 5), ("forward", 10)] {
            let kind = format!("{direction}_world_modeling_ordering_{steps}_steps");
            let id = qa
                .lines()
                .map(|l| serde_json::from_str::<Value>(l).expect("record"))
                .find(|r| r["type"] == kind.as_str())
                .map(|r| r["id"].as_str().expect("id").to_owned())
                .expect("a sample item of each kind");
            sample_items.push(json!({"item": id, "steps": steps}));
        }
        let ids: Vec<String> = sample_items
            .iter()
            .map(|i| i["item"].as_str().expect("id").to_owned())
            .collect();
        crate::annotate::assign_in(
            &server,
            "sample",
            annotator,
            &ids.iter().map(String::as_str).collect::<Vec<_>>(),
        )
        .await;
    }

    let params = json!({
        "mode": "e2e",
        "base": server.url(""),
        "invite": format!("/invite/{token}"),
        "forward": forward,
        "inverse": inverse,
        "wide": wide,
        "sample": sample_items,
        "chromium": CHROMIUM,
        "failure_dir": env!("CARGO_TARGET_TMPDIR"),
    });
    let found = run_node("annotate.mjs", params).await;
    assert_eq!(
        found["after_reload"],
        json!(["Slot 1: Next State 2", "Slot 2: empty"])
    );
    assert_eq!(found["announced"], "Next State 2 placed in slot 1.");
    assert_eq!(found["announced_last"], "Action 2 placed in slot 2.");
    assert_eq!(found["wide_checked"], 2);
    assert_eq!(found["sample_checked"], sample_items.len(), "{found}");
    assert_eq!(found["console_errors"], 0);

    let mut conn = server.pool.acquire().await.expect("conn");
    let f: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT id FROM items WHERE item_id = $1").bind(&forward)
    )
    .expect("forward");
    let i: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar("SELECT id FROM items WHERE item_id = $1").bind(&inverse)
    )
    .expect("inverse");
    let fwd = store::annotations::annotation(&mut conn, annotator, f)
        .await
        .expect("query")
        .expect("forward answered");
    assert_eq!(fwd.answer, Some(vec![2, 1]));
    let t = fwd.telemetry;
    assert_eq!((t.placements, t.swaps, t.clears, t.undos), (2, 0, 0, 0));
    let first = t.time_to_first_placement_ms.expect("first placement time");
    assert!(first <= t.time_on_item_ms && t.time_on_item_ms > 0, "{t:?}");
    let inv = store::annotations::annotation(&mut conn, annotator, i)
        .await
        .expect("query")
        .expect("inverse answered");
    assert_eq!(inv.answer, Some(vec![3, 2, 1]));
    let t = inv.telemetry;
    assert_eq!((t.placements, t.swaps, t.clears, t.undos), (6, 2, 1, 1));
    assert!(t.time_to_first_placement_ms.expect("set") <= t.time_on_item_ms);
    // Both answers equal the ground truth, and the verifier agrees.
    let dataset = store::datasets::by_name(&mut conn, "mini")
        .await
        .expect("q")
        .expect("mini");
    let report =
        enact_hub::app::leaderboard::human_performance(&server.pool.clone().into(), &dataset)
            .await
            .expect("query")
            .expect("answers");
    let overall = report.overall.expect("overall");
    assert_eq!(
        (overall.totals.count, overall.totals.task_accuracy),
        (2, 1.0)
    );
    drop(conn);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_newcomer_follows_the_demo_link_and_annotates_at_once() {
    if !browser_available() {
        return;
    }
    use std::io::BufRead;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_enact-hub"))
        .args(["serve", "--demo", "--addr", "127.0.0.1:0"])
        .env("RUST_LOG", "warn")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start serve --demo");
    let stdout = child.stdout.take().expect("stdout");
    let link = tokio::task::spawn_blocking(move || {
        std::io::BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
            .find(|l| l.starts_with("http://") && l.contains("/login/link/"))
    })
    .await
    .expect("join");
    let Some(link) = link else {
        let _ = child.kill();
        panic!("serve --demo printed no login link");
    };
    let found = run_node(
        "demo.mjs",
        json!({"link": link, "chromium": CHROMIUM, "failure_dir": env!("CARGO_TARGET_TMPDIR")}),
    )
    .await;
    // A graceful stop, so the server removes its temporary demo database.
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let _ = child.wait();
    assert_eq!(found["done"], json!(["forward", "inverse"]), "{found}");
    let human = found["human_row"].as_str().expect("a Human row");
    assert!(human.contains("1 annotator, 2 answers"), "{human}");
}

/// The paper's ablation figure for a study with three families (two variants in one), drawn
/// on the study page: every label inside its figure and none running into another.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_study_of_three_families_draws_every_label_whole() {
    if !browser_available() {
        return;
    }
    let rig = |change: &dyn Fn(&mut enact_hub::core::world::CameraRig)| {
        let mut rig = enact_hub::core::world::CameraRig {
            image_size: 96,
            ..Default::default()
        };
        change(&mut rig);
        rig
    };
    let (server, records) = crate::studies::world_with_variants(&[
        ("world-fov30", rig(&|r| r.fov_deg = 30.0)),
        ("world-fov80", rig(&|r| r.fov_deg = 80.0)),
        ("world-low", rig(&|r| r.height_m = 1.0)),
        ("world-skin", rig(&|r| r.robot_colour = [224, 172, 105])),
    ])
    .await;
    let token = create_study(
        &server,
        json!({
            "name": "three",
            "baseline": crate::studies::BASELINE,
            "variants": [
                "Camera FOV/Aperture 30=world-fov30",
                "Camera height/Low camera (1.0 m)=world-low",
                "Camera FOV/Aperture 80=world-fov80",
                "Robot appearance/Skin colour=world-skin",
            ],
        }),
    )
    .await;
    let datasets = [
        crate::studies::BASELINE,
        "world-fov30",
        "world-fov80",
        "world-low",
        "world-skin",
    ];
    for (d, dataset) in datasets.iter().enumerate() {
        let wrong: Vec<usize> = (0..records.len()).filter(|i| i % (d + 2) == 0).collect();
        server
            .call(
                reqwest::Method::POST,
                &format!("/api/v1/datasets/{dataset}/submissions?model=gpt-5-mini"),
            )
            .bearer(&token)
            .body(answers(&records, &wrong))
            .expect(201)
            .await;
    }
    let shot = std::env::var("ENACT_STUDY_SHOT").ok();
    let found = run_node(
        "study.mjs",
        json!({
            "url": server.url("/studies/three?row=model:gpt-5-mini"),
            "chromium": CHROMIUM,
            "shot": shot,
        }),
    )
    .await;
    assert_eq!(found["panels"], 3, "{found}");
    assert_eq!(
        found["cell_rows"], 8,
        "four variants, two directions: {found}"
    );
    for figure in ["heatmap", "handedness"] {
        let measured = &found[figure];
        assert!(measured["texts"].as_u64() > Some(10), "{figure}: {found}");
        assert_eq!(
            measured["outside"],
            json!([]),
            "{figure}: labels cut: {found}"
        );
    }
    assert_eq!(found["heatmap"]["overlapping"], json!([]), "{found}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_gold_item_renders_in_chromium_exactly_like_any_other_item_apart_from_its_id() {
    if !browser_available() {
        return;
    }
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        // Two forward and two inverse items of L = 3 and of L = 4.
        let written = write_balanced_release(&root, &[3, 4], 2);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records: Vec<Value> = records.lock().expect("lock").clone();
    let id = |i: usize| records[i]["id"].as_str().expect("id").to_owned();
    let hub = enact_hub::app::Hub::from(server.pool.clone());
    // Items 0 and 1 are both forward L = 3; 2 and 3 inverse L = 3: one gold item of each.
    let choice = enact_hub::core::gold::GoldChoice::List(vec![id(0), id(2)]);
    let rate = enact_hub::core::gold::GoldRate::new(2).expect("rate");
    enact_hub::app::gold::set(&hub, &tester(), "mini", &choice, rate)
        .await
        .expect("gold set");
    let token = new_token();
    let annotator = {
        let mut tx = write_tx(&server.pool).await;
        let id = store::annotations::create_annotator(&mut tx, "gus", false, &token_hash(&token))
            .await
            .expect("insert");
        tx.commit().await.expect("commit");
        id
    };
    let ordinary = [id(1), id(3)];
    enact_hub::app::annotation::assign(
        &hub,
        &tester(),
        "mini",
        &enact_hub::app::annotation::Assignment::List {
            annotator,
            item_ids: ordinary.to_vec(),
        },
    )
    .await
    .expect("assigned");
    // The invite is single use: one browser session opens all four pages.
    let pages = [id(0), id(1), id(2), id(3)];
    let found = run_node(
        "gold.mjs",
        json!({
            "base": server.url(""),
            "invite": format!("/invite/{token}"),
            "items": pages,
            "chromium": CHROMIUM,
        }),
    )
    .await;
    assert_eq!(found["console_errors"], 0, "{found}");
    let shapes = found["shapes"].as_array().expect("shapes");
    // The comparison sees markup: a forward and an inverse page differ.
    assert_ne!(shapes[0], shapes[2]);
    for pair in [0, 2] {
        assert!(
            shapes[pair].as_array().expect("elements").len() > 20,
            "{found}"
        );
        assert_eq!(
            shapes[pair],
            shapes[pair + 1],
            "gold {} and ordinary {} differ",
            pages[pair],
            pages[pair + 1]
        );
    }
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_annotator_reading_chinese_finishes_both_directions_by_keyboard() {
    if !browser_available() {
        return;
    }
    let (server, records) = spawn_app_with_release().await;
    let id = |i: usize| records[i]["id"].as_str().expect("id").to_owned();
    // write_release: forward then inverse for each L; 0 = forward 3, 1 = inverse 3.
    let (forward, inverse) = (id(0), id(1));
    let token = new_token();
    let annotator = {
        let mut tx = write_tx(&server.pool).await;
        let id = store::annotations::create_annotator(&mut tx, "li", false, &token_hash(&token))
            .await
            .expect("insert");
        tx.commit().await.expect("commit");
        id
    };
    assign(&server, annotator, &[&forward, &inverse]).await;
    let params = json!({
        "base": server.url(""),
        "invite": format!("/invite/{token}"),
        "forward": forward,
        "inverse": inverse,
        "forward_slots": 2,
        "inverse_slots": 2,
        "chromium": CHROMIUM,
        "failure_dir": env!("CARGO_TARGET_TMPDIR"),
    });
    let found = run_node("locale.mjs", params).await;
    // What the live region said, as the accessibility tree holds it, after each move.
    let announced = |k: &str| -> Vec<String> {
        found[k]
            .as_array()
            .expect("announcements")
            .iter()
            .map(|v| v.as_str().expect("text").to_owned())
            .collect()
    };
    let forward_said = announced("forward_announced");
    assert!(
        forward_said[0].contains("Next State 1 已放入槽位 1。"),
        "{forward_said:?}"
    );
    let inverse_said = announced("inverse_announced");
    assert!(
        inverse_said[1].contains("Action 2 已放入槽位 2。"),
        "{inverse_said:?}"
    );
    assert_eq!(found["console_errors"], 0);
    // Both answers are stored, as placed.
    let answered: i64 = db!(
        server.pool,
        fetch_one,
        sqlx::query_scalar(
            "SELECT COUNT(*) FROM annotations WHERE annotator = $1 AND answer IS NOT NULL"
        )
        .bind(annotator)
    )
    .expect("count");
    assert_eq!(answered, 2);
    server.stop().await;
}

/// The public and annotator pages with something on each: the `mini` release and a second
/// import of it (`mini-b`) as the variant of a study `camera`; on both, a perfect model, a
/// reversed one and one named like the demo's chance baseline (the longest row label of the
/// error analysis); two annotators (`ana`, `bo`) with both directions' first items assigned and
/// single-use invites; an admin `boss` with a password, for the agreement report.
struct PublicWorld {
    server: TestServer,
    records: Vec<Value>,
    invites: Vec<String>,
    /// The submissions on `mini`: exact, reversed, chance.
    submissions: Vec<i64>,
}

impl PublicWorld {
    async fn new() -> PublicWorld {
        let (server, records) = spawn_app_with_release_as(&["mini", "mini-b"]).await;
        let id = |i: usize| records[i]["id"].as_str().expect("id").to_owned();
        let mut invites = Vec::new();
        for name in ["ana", "bo"] {
            let token = new_token();
            let annotator = {
                let mut tx = write_tx(&server.pool).await;
                let id =
                    store::annotations::create_annotator(&mut tx, name, false, &token_hash(&token))
                        .await
                        .expect("insert");
                tx.commit().await.expect("commit");
                id
            };
            assign(&server, annotator, &[&id(0), &id(1)]).await;
            invites.push(format!("/invite/{token}"));
        }
        crate::annotate::annotator(&server, "boss", true).await;
        let admin = create_study(
            &server,
            json!({
                "name": "camera",
                "baseline": "mini",
                "variants": ["Camera height/Low camera (1.0 m)=mini-b"],
            }),
        )
        .await;
        let chance = enact_hub::core::demo::CHANCE_BASELINE_MODEL.replace(' ', "%20");
        let mut submissions = Vec::new();
        for dataset in ["mini", "mini-b"] {
            for (model, wrong) in [
                ("exact", vec![]),
                ("reversed", vec![0, 1, 2, 3]),
                (chance.as_str(), vec![1, 2]),
            ] {
                let body = answers(&records, &wrong);
                let reply =
                    submit_to(&server, dataset, &format!("model={model}"), &admin, body).await;
                assert_eq!(reply.status, 201, "{}", reply.text);
                if dataset == "mini" {
                    submissions.push(reply.id());
                }
            }
        }
        // Three of the paper's published rows, so that the paper page marks cells and checks
        // a reproduction ("exact" is not among them; GPT-5 is compared with nothing).
        for model in enact_hub::core::paper::enact_paper_results()
            .into_iter()
            .filter(|m| {
                ["GPT-5", "GPT-5 mini", "GPT-5 nano", "Human Performance"]
                    .contains(&m.model.as_str())
            })
        {
            server
                .call(reqwest::Method::POST, "/api/v1/datasets/mini/reported")
                .bearer(&admin)
                .json(&serde_json::to_value(&model).expect("json"))
                .expect(201)
                .await;
        }
        // Public answers: the item pages show every row's answer, with the verifier's reasons.
        set_mini_answers(
            &server.pool,
            enact_hub::core::dataset::AnswerVisibility::Public,
        )
        .await;
        PublicWorld {
            server,
            records,
            invites,
            submissions,
        }
    }

    fn item(&self, i: usize) -> String {
        self.records[i]["id"].as_str().expect("id").to_owned()
    }

    /// The pages an annotator reaches: the queue and a forward and an inverse item.
    fn annotator_pages(&self) -> Vec<String> {
        vec![
            "/annotate".to_owned(),
            format!("/annotate/mini/{}", self.item(0)),
            format!("/annotate/mini/{}", self.item(1)),
        ]
    }

    /// The public pages: home, dataset and items (with every answer), leaderboard, a
    /// comparison of two rows, the explorer (all items, and a pattern sorted by a row), error
    /// analyses, studies.
    fn public_pages(&self) -> Vec<String> {
        vec![
            "/".to_owned(),
            "/datasets/mini".to_owned(),
            format!("/datasets/mini/items/{}", self.item(0)),
            format!("/datasets/mini/items/{}", self.item(1)),
            "/leaderboard/mini".to_owned(),
            "/datasets/mini/paper?intervals=1".to_owned(),
            "/datasets/mini/compare?a=exact&b=reversed".to_owned(),
            "/datasets/mini/explore".to_owned(),
            format!(
                "/datasets/mini/explore?pattern=models-disagree&sort=wrong:{}",
                self.submissions[1]
            ),
            "/leaderboard/mini/errors".to_owned(),
            format!("/leaderboard/mini/errors/{}", self.submissions[2]),
            "/studies".to_owned(),
            "/studies/camera".to_owned(),
            "/login".to_owned(),
            "/datasets/no-such-dataset".to_owned(),
        ]
    }
}

/// Admin pages the layout and accessibility checks cover (English only, as admin pages are).
const ADMIN_PAGES: [&str; 2] = [
    "/admin/datasets/mini/report",
    "/admin/datasets/mini/reported",
];

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn axe_finds_no_wcag_violation_on_the_pages_in_either_language() {
    if !browser_available() {
        return;
    }
    assert!(
        browser_dir().join("node_modules/axe-core").is_dir(),
        "tests/browser/node_modules/axe-core is missing: run `npm ci` in tests/browser \
         (scripts/test.sh does)"
    );
    let world = PublicWorld::new().await;
    let pages: Vec<String> = world
        .public_pages()
        .into_iter()
        .chain(world.annotator_pages())
        .collect();
    let params = json!({
        "base": world.server.url(""),
        "invites": world.invites,
        "pages": pages,
        "admin": {"name": "boss", "password": crate::annotate::PASSWORD},
        "admin_pages": ADMIN_PAGES,
        "locales": ["en-US", "zh-CN"],
        "chromium": CHROMIUM,
    });
    let found = run_node("axe.mjs", params).await;
    assert_eq!(
        found["checked"],
        2 * (pages.len() + ADMIN_PAGES.len() + 1),
        "{found}"
    );
    let violations = found["violations"].as_array().expect("violations");
    assert!(
        violations.is_empty(),
        "axe-core found {} violations:\n{}",
        violations.len(),
        violations
            .iter()
            .map(Value::to_string)
            .collect::<Vec<_>>()
            .join("\n")
    );
    world.server.stop().await;
}

/// The pseudo-locale (English wrapped in ⟦…⟧, 40 % longer) on right-to-left pages, at a
/// desktop's 1280×800 and a phone's 390×844: nothing scrolls sideways, leaves the viewport,
/// overlaps another text or is cut by its figure, on the annotation pages, the public pages and
/// the agreement report (English, turned right-to-left by the script).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pseudo_locale_pages_lay_out_right_to_left_without_overflow_or_overlap() {
    if !browser_available() {
        return;
    }
    let world = PublicWorld::new().await;
    let groups = json!([
        {"as": "annotator", "translated": true, "pages": world.annotator_pages()},
        {"as": "anyone", "translated": true, "pages": world.public_pages()},
        {"as": "admin", "translated": false, "pages": ADMIN_PAGES},
    ]);
    let found = run_node(
        "layout.mjs",
        json!({
            "base": world.server.url(""),
            "invite": world.invites[0],
            "password": crate::annotate::PASSWORD,
            "admin": {"name": "boss", "password": crate::annotate::PASSWORD},
            "cookie": enact_hub::web::i18n::Locale::PseudoRtl.tag(),
            "groups": groups,
            "viewports": [[1280, 800], [390, 844]],
            "chromium": CHROMIUM,
            "failure_dir": env!("CARGO_TARGET_TMPDIR"),
        }),
    )
    .await;
    // The one console error expected: the missing dataset's page is a 404.
    let unexpected: Vec<&Value> = found["consoleErrors"]
        .as_array()
        .expect("console errors")
        .iter()
        .filter(|e| {
            !e.as_str()
                .is_some_and(|e| e.contains("/datasets/no-such-dataset"))
        })
        .collect();
    assert!(unexpected.is_empty(), "{unexpected:?}");
    let checked = found["checked"].as_array().expect("checked pages");
    let pages = world.annotator_pages().len() + world.public_pages().len() + ADMIN_PAGES.len();
    assert_eq!(checked.len(), 2 * pages, "{found}");
    let mut problems = Vec::new();
    for page in checked {
        let path = page["path"].as_str().expect("path");
        if !ADMIN_PAGES.contains(&path) {
            // Served in the pseudo-locale: right to left, and its text from the catalogue.
            assert_eq!(page["dir"], "rtl", "{page}");
            assert_eq!(page["lang"], "ar-XB", "{page}");
            assert!(page["pseudo"].as_u64() > Some(3), "{page}");
        }
        for problem in page["problems"].as_array().expect("problems") {
            problems.push(format!("{} at {}: {problem}", path, page["viewport"]));
        }
    }
    assert!(
        problems.is_empty(),
        "{} layout problems (screenshots in {}):\n{}",
        problems.len(),
        env!("CARGO_TARGET_TMPDIR"),
        problems.join("\n")
    );
    world.server.stop().await;
}

/// Creates the study `body` describes over the API as a new admin; the admin's API token.
async fn create_study(server: &TestServer, body: Value) -> String {
    let (_, token) = api_token(
        &server.pool,
        "admin",
        enact_hub::core::credentials::Role::Admin,
        None,
        None,
    )
    .await;
    server
        .call(reqwest::Method::POST, "/api/v1/admin/studies")
        .bearer(&token)
        .json(&body)
        .expect(201)
        .await;
    token
}

/// A server-side model run's page in Chromium: labelled controls, pause and resume by keyboard,
/// and progress brought to the end by the page's script without a reload.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_run_page_follows_its_run_live_and_is_paused_and_resumed_by_keyboard() {
    use enact_hub::app::Hub;
    use enact_hub::app::jobs::Worker;
    use enact_hub::app::runs;
    use std::time::Duration;

    use crate::runs::{answer_text, run_fixture, scripts, spec};
    use crate::server_runs::{KEY_VARIABLE, fast, keyed};
    use crate::standin::{StandIn, StandInConfig, Step};

    if !browser_available() {
        return;
    }
    let (dir, pool, records) = run_fixture(2).await;
    let gate = std::sync::Arc::new(tokio::sync::Semaphore::new(2));
    let standin = StandIn::start(StandInConfig {
        scripts: scripts(&dir.path().join("release"), &records, |_, r| {
            vec![Step::Answer(answer_text(r, true))]
        }),
        // Two items answered, the third held until the page has paused the run: the page sees
        // the run under way however slowly Chromium starts on a loaded machine. After the
        // pause, slow enough that the page loaded after the resume sees the run unfinished.
        gate: Some(gate.clone()),
        latency: Duration::from_millis(300),
        tokens_per_image: 85,
        ..StandInConfig::default()
    })
    .await;
    let hub = keyed(Hub::from(pool.clone()));
    let server = serve_hub(hub.clone(), pool.clone(), dir, &Default::default()).await;
    crate::annotate::annotator(&server, "boss", true).await;
    let calls = runs::RunCalls {
        key_variable: Some(KEY_VARIABLE.to_owned()),
        concurrency: 1,
        max_retries: 1,
        timeout_s: 10.0,
    };
    let (run, job) = runs::start(&hub, &tester(), &spec(&standin, "watched"), &calls)
        .await
        .expect("started");
    let worker = Worker::spawn(hub.clone(), enact_hub::app::job_handlers(), fast());
    // The rest of the items are let through once the page has paused the run.
    let opener = {
        let (hub, gate) = (hub.clone(), gate.clone());
        tokio::spawn(async move {
            let deadline = tokio::time::Instant::now() + Duration::from_secs(120);
            loop {
                let state = enact_hub::app::jobs::get(&hub, job)
                    .await
                    .expect("read the run's job")
                    .map(|j| j.state);
                if state == Some(enact_hub::store::jobs::JobState::Paused) {
                    break;
                }
                assert!(
                    tokio::time::Instant::now() < deadline,
                    "the page never paused the run (job {state:?})"
                );
                tokio::time::sleep(Duration::from_millis(50)).await;
            }
            gate.add_permits(1_000);
        })
    };
    let found = run_node(
        "run_progress.mjs",
        json!({
            "base": server.url(""), "name": "boss", "password": crate::annotate::PASSWORD,
            "run": run.id, "chromium": CHROMIUM,
        }),
    )
    .await;
    opener.await.expect("the gate opener");
    worker.stop().await;
    assert_eq!(found["unlabelled"], json!([]), "{found}");
    assert!(
        found["paused"]["notice"]
            .as_str()
            .is_some_and(|n| n.starts_with("Paused")),
        "{found}"
    );
    assert_eq!(found["paused"]["resume_visible"], true, "{found}");
    assert_eq!(found["paused"]["pause_visible"], false, "{found}");
    let n = records.len();
    assert_eq!(found["last"]["stage"], "done (submitted)", "{found}");
    assert_eq!(found["last"]["done"], format!("{n} of {n}"), "{found}");
    assert_ne!(found["last"]["cost"], "$0.0000", "{found}");
    assert_eq!(found["last"]["pause_visible"], false, "{found}");
    assert_eq!(found["last"]["cancel_visible"], false, "{found}");
    assert_eq!(found["navigations"], 0, "the page was reloaded: {found}");
    // What the page showed when it loaded after the resume was not the end: its script
    // brought it there. (Its count may already be complete: items in flight when the run was
    // paused finish during the pause, so only the stage tells the end apart; queued or, if
    // the worker took it at once, running.)
    assert!(
        found["resumed"]["stage"]
            .as_str()
            .is_some_and(|s| s.starts_with("queued") || s.starts_with("running")),
        "{found}"
    );
    server.stop().await;
}
