//! Annotator quality control: gold items mixed into the queues at their rate, a careful and a
//! careless annotator told apart on the quality API and page (figures recomputed here from
//! the stored rows), exclusion from the Human row, the audit log, and gold items that look
//! like any other item.

use std::collections::{BTreeMap, HashSet};

use enact_hub::app::Hub;
use enact_hub::app::annotation::{self, Assignment};
use enact_hub::core::audit::AuditFilter;
use enact_hub::core::credentials::Role;
use reqwest::Method;
use serde_json::{Value, json};

use crate::annotate::{annotator, logged_in_on};
use crate::helpers::*;

/// Seconds the careless annotator spends on an item.
const CARELESS_SECONDS: i64 = 2;

/// The quality figures of "mini".
const QUALITY: &str = "/api/v1/admin/annotators/quality?dataset=mini";

/// Items per direction × L (L = 3 and 4): 24 items.
const PER_CELL: u32 = 6;

/// A server with the 24-item release as "mini", its records, and an admin token.
async fn server_with_items() -> (TestServer, Vec<Value>, String) {
    let records = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let shared = records.clone();
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        let written = write_balanced_release(&root, &[3, 4], PER_CELL);
        import(&pool, &root, &options("mini")).await;
        *shared.lock().expect("lock") = written;
    })
    .await;
    let records = records.lock().expect("lock").clone();
    let (_, token) = api_token(&server.pool, "boss", Role::Admin, None, None).await;
    (server, records, token)
}

fn id(record: &Value) -> String {
    record["id"].as_str().expect("id").to_owned()
}

fn labels(value: &Value) -> Vec<u8> {
    value
        .as_array()
        .expect("a label list")
        .iter()
        .map(|v| u8::try_from(v.as_u64().expect("a label")).expect("small"))
        .collect()
}

/// A seeded shuffle of `gt` that is never `gt` itself (xorshift; the test's own randomness).
fn careless_order(gt: &[u8], state: &mut u64) -> Vec<u8> {
    let mut order = gt.to_vec();
    for i in (1..order.len()).rev() {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        let j = usize::try_from(*state % (i as u64 + 1)).expect("small");
        order.swap(i, j);
    }
    if order == gt {
        order.reverse();
    }
    order
}

/// Works `name`'s whole queue in order over HTTP, each item taking `seconds(i)` (the draft's
/// start moved back by that much before the answer), answering with `answer(item)`.
pub(crate) async fn work_queue(
    server: &TestServer,
    name: &str,
    annotator_id: i64,
    seconds: impl Fn(usize) -> i64,
    mut answer: impl FnMut(&str) -> Vec<u8>,
) {
    let hub = Hub::from(server.pool.clone());
    let queue = annotation::queue(&hub, annotator_id).await.expect("queue");
    let (mut browser, csrf) = logged_in_on(server, name, "/annotate").await;
    for (i, entry) in queue.iter().enumerate() {
        let page = browser
            .get(&format!("/annotate/mini/{}", entry.item_id))
            .await;
        assert_eq!(page.status(), 200, "{name}: {}", entry.item_id);
        db!(
            server.pool,
            execute,
            sqlx::query(
                "UPDATE drafts SET started_at_ms = started_at_ms - $1 WHERE annotator = $2 \
                 AND item = (SELECT id FROM items WHERE item_id = $3)"
            )
            .bind(seconds(i) * 1000)
            .bind(annotator_id)
            .bind(&entry.item_id)
        )
        .expect("draft moved back");
        let slots = answer(&entry.item_id);
        let r = browser
            .post_json(
                &format!("/annotate/mini/{}/submit", entry.item_id),
                Some(&csrf),
                &json!({"slots": slots, "counts": {"placements": slots.len(), "swaps": 0, "clears": 0, "undos": 0}}),
            )
            .await;
        assert_eq!(r.status(), 200, "{name}: {}", entry.item_id);
    }
}

/// Works both annotators' queues over HTTP: "careful" answers the truth and takes 20 s and
/// more per item, "careless" a seeded wrong order in [`CARELESS_SECONDS`].
async fn work_careful_and_careless(
    server: &TestServer,
    careful: i64,
    careless: i64,
    gts: &BTreeMap<String, Vec<u8>>,
) {
    work_queue(
        server,
        "careful",
        careful,
        |i| 20 + i as i64,
        |item| gts[item].clone(),
    )
    .await;
    let mut state = 0x9E37_79B9_7F4A_7C15;
    work_queue(
        server,
        "careless",
        careless,
        |_| CARELESS_SECONDS,
        |item| careless_order(&gts[item], &mut state),
    )
    .await;
}

/// One stored answer: annotator, item id, answer, time on item and the stored pairwise accuracy.
type StoredRow = (String, String, String, i64, Option<f64>);

async fn stored_answers(server: &TestServer) -> Vec<StoredRow> {
    db!(
        server.pool,
        fetch_all,
        sqlx::query_as::<_, StoredRow>(
            "SELECT a.name, i.item_id, n.answer, n.time_on_item_ms, n.pairwise_accuracy \
             FROM annotations n JOIN annotators a ON a.id = n.annotator \
             JOIN items i ON i.id = n.item ORDER BY a.name, i.item_id"
        )
    )
    .expect("answers")
}

/// The type-7 quantile (numpy's default) of ascending values.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let position = q * (sorted.len() - 1) as f64;
    let below = position.floor() as usize;
    let above = (below + 1).min(sorted.len() - 1);
    sorted[below] + (position - below as f64) * (sorted[above] - sorted[below])
}

fn close(actual: &Value, expected: f64, what: &str) {
    let actual = actual
        .as_f64()
        .unwrap_or_else(|| panic!("{what}: {actual} is not a number"));
    assert!(
        (actual - expected).abs() < 1e-9,
        "{what}: {actual} where {expected} was expected"
    );
}

/// Figures of one annotator computed from the stored rows, independently of the service.
struct Expected {
    gold_ta: f64,
    gold_pa: f64,
    median: f64,
    p10: f64,
    fast: f64,
}

fn expected(
    rows: &[StoredRow],
    name: &str,
    gold: &HashSet<String>,
    gts: &BTreeMap<String, Vec<u8>>,
) -> Expected {
    let mine: Vec<&StoredRow> = rows.iter().filter(|r| r.0 == name).collect();
    let gold_rows: Vec<&&StoredRow> = mine.iter().filter(|r| gold.contains(&r.1)).collect();
    let right = gold_rows
        .iter()
        .filter(|r| labels(&serde_json::from_str(&r.2).expect("json")) == gts[&r.1])
        .count();
    let pas: Vec<f64> = gold_rows.iter().filter_map(|r| r.4).collect();
    let mut seconds: Vec<f64> = mine.iter().map(|r| r.3 as f64 / 1000.0).collect();
    seconds.sort_by(f64::total_cmp);
    Expected {
        gold_ta: right as f64 / gold_rows.len() as f64,
        gold_pa: pas.iter().sum::<f64>() / pas.len() as f64,
        median: quantile(&seconds, 0.5),
        p10: quantile(&seconds, 0.1),
        fast: seconds.iter().filter(|s| **s < 5.0).count() as f64 / seconds.len() as f64,
    }
}

/// The audit entries of `action` (or of its noun alone), newest first.
async fn audit_of(hub: &Hub, action: &str) -> Vec<enact_hub::core::audit::AuditEntry> {
    enact_hub::app::audit::list(
        hub,
        AuditFilter {
            action: Some(action.to_owned()),
            limit: 10,
            ..AuditFilter::default()
        },
    )
    .await
    .expect("audit")
}

/// Appends the listed items of "mini" to an annotator's queue, as an admin would (the gold mix
/// follows).
pub(crate) async fn assign_listed(hub: &Hub, annotator: i64, item_ids: &[String]) {
    annotation::assign(
        hub,
        &tester(),
        "mini",
        &Assignment::List {
            annotator,
            item_ids: item_ids.to_vec(),
        },
    )
    .await
    .expect("assigned");
}

/// The Human row of "mini"'s leaderboard.
async fn human_row(server: &TestServer) -> Value {
    let board = server
        .call(Method::GET, "/api/v1/datasets/mini/leaderboard")
        .expect(200)
        .await
        .json();
    board["rows"]
        .as_array()
        .expect("rows")
        .iter()
        .find(|r| r["source"] == "human")
        .unwrap_or_else(|| panic!("no Human row: {board}"))
        .clone()
}

/// `method path` with the admin token and no body, answered 200: its JSON.
async fn as_admin(server: &TestServer, admin: &str, method: Method, path: &str) -> Value {
    server
        .call(method, path)
        .bearer(admin)
        .expect(200)
        .await
        .json()
}

#[tokio::test]
async fn gold_items_tell_a_careful_annotator_from_a_careless_one_and_exclusion_cleans_the_human_row()
 {
    let (server, records, admin) = server_with_items().await;
    let gts: BTreeMap<String, Vec<u8>> = records
        .iter()
        .map(|r| (id(r), labels(&r["gt_answer"])))
        .collect();
    // One gold item in each direction × L cell; one in every 5 queue items.
    let gold_ids: Vec<String> = (0..4)
        .map(|cell| id(&records[cell * PER_CELL as usize]))
        .collect();
    let gold: HashSet<String> = gold_ids.iter().cloned().collect();
    let set = server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/gold")
        .bearer(&admin)
        .json(&json!({"rate": 5, "items": gold_ids}))
        .expect(200)
        .await
        .json();
    assert_eq!(set["gold"]["items"].as_array().expect("items").len(), 4);
    assert_eq!(set["gold"]["rate"], 5);

    // Both annotators get the same 16 ordinary items; the gold mix adds 4 to each queue.
    let ordinary: Vec<String> = records
        .iter()
        .map(id)
        .filter(|i| !gold.contains(i))
        .take(16)
        .collect();
    let hub = Hub::from(server.pool.clone());
    let careful = annotator(&server, "careful", false).await;
    let careless = annotator(&server, "careless", false).await;
    for who in [careful, careless] {
        assign_listed(&hub, who, &ordinary).await;
        let queue = annotation::queue(&hub, who).await.expect("queue");
        assert_eq!(queue.len(), 20);
        for (i, entry) in queue.iter().enumerate() {
            assert_eq!(
                gold.contains(&entry.item_id),
                i % 5 == 4,
                "queue position {i}: {}",
                entry.item_id
            );
        }
    }

    work_careful_and_careless(&server, careful, careless, &gts).await;

    // The API's figures against the ones computed here from the stored rows.
    let rows = stored_answers(&server).await;
    let quality = as_admin(&server, &admin, Method::GET, QUALITY).await;
    let annotators = quality["annotators"].as_array().expect("annotators");
    assert_eq!(annotators.len(), 2, "{quality}");
    for a in annotators {
        let name = a["name"].as_str().expect("name");
        let want = expected(&rows, name, &gold, &gts);
        assert_eq!(a["items_done"], 20, "{name}");
        assert_eq!(a["gold_answered"], 4, "{name}");
        close(&a["gold_task_accuracy"], want.gold_ta, name);
        close(&a["gold_pairwise_accuracy"], want.gold_pa, name);
        close(&a["median_seconds"], want.median, name);
        close(&a["lower_decile_seconds"], want.p10, name);
        close(&a["fast_share"], want.fast, name);
        close(&a["skip_rate"], 0.0, name);
        assert_eq!(a["shared_items"], 20, "{name}");
        // The careless answers are never the ground truth, so the two never agree.
        close(&a["exact_agreement"], 0.0, name);
    }
    let by_name = |name: &str| {
        annotators
            .iter()
            .find(|a| a["name"] == name)
            .expect("listed")
            .clone()
    };
    let (good, bad) = (by_name("careful"), by_name("careless"));
    close(&good["gold_task_accuracy"], 1.0, "careful");
    close(&bad["gold_task_accuracy"], 0.0, "careless");
    assert!(good["median_seconds"].as_f64() > Some(20.0));
    close(&bad["fast_share"], 1.0, "careless");
    assert!(
        good["gold_task_accuracy_interval"]["low"].as_f64()
            > bad["gold_task_accuracy_interval"]["high"].as_f64(),
        "the intervals part them: {good} {bad}"
    );

    // The page highlights the careless row under an 80% bar, and only it.
    annotator(&server, "lead", true).await;
    let (mut lead, _) = logged_in_on(&server, "lead", "/annotate").await;
    let (status, html) = lead.text("/admin/quality?dataset=mini&bar=80").await;
    assert_eq!(status, 200, "{html}");
    assert_eq!(html.matches("class=\"below-bar\"").count(), 1, "{html}");
    let marked = html
        .find("class=\"below-bar\"")
        .expect("a row under the bar");
    let row = &html[marked..marked + 200];
    assert!(
        row.contains(">careless <span class=\"tag\">below bar</span>"),
        "{row}"
    );
    assert!(html.contains("100.0%"), "careful's gold TA shown: {html}");

    // Gold answers never count in the Human row: 16 + 16 ordinary answers, 20 coverable items.
    let human = human_row(&server).await;
    assert_eq!(human["human"]["answers"], 32, "{human}");
    assert_eq!(human["human"]["dataset_items"], 20, "{human}");
    assert_eq!(human["human"]["gold_items"], 4, "{human}");
    assert_eq!(human["human"]["annotators"], 2, "{human}");

    // Excluding the careless annotator leaves exactly the careful one's figures.
    let exclusion = "/api/v1/admin/datasets/mini/exclusions/careless";
    as_admin(&server, &admin, Method::PUT, exclusion).await;
    let again = as_admin(&server, &admin, Method::PUT, exclusion).await;
    assert_eq!(
        again["changed"], false,
        "excluding twice changes nothing: {again}"
    );
    let human = human_row(&server).await;
    assert_eq!(human["human"]["answers"], 16, "{human}");
    assert_eq!(human["human"]["annotators"], 1, "{human}");
    assert_eq!(human["human"]["excluded_annotators"], 1, "{human}");
    let careful_rows: Vec<&StoredRow> = rows
        .iter()
        .filter(|r| r.0 == "careful" && !gold.contains(&r.1))
        .collect();
    let direction_of = |item: &str| {
        records
            .iter()
            .find(|r| id(r) == item)
            .map(|r| {
                if r["type"].as_str().unwrap_or("").contains("forward") {
                    "forward"
                } else {
                    "inverse"
                }
            })
            .expect("record")
    };
    for direction in ["forward", "inverse"] {
        let mine: Vec<&&StoredRow> = careful_rows
            .iter()
            .filter(|r| direction_of(&r.1) == direction)
            .collect();
        let right = mine
            .iter()
            .filter(|r| labels(&serde_json::from_str(&r.2).expect("json")) == gts[&r.1])
            .count();
        let pa: f64 = mine.iter().filter_map(|r| r.4).sum::<f64>() / mine.len() as f64;
        let total = &human[direction]["total"];
        assert_eq!(total["count"], mine.len(), "{direction}: {human}");
        close(
            &total["task_accuracy"],
            right as f64 / mine.len() as f64,
            direction,
        );
        close(&total["pairwise_accuracy"], pa, direction);
    }
    close(&human["overall"]["task_accuracy"], 1.0, "overall");
    assert_eq!(human["overall"]["count"], 16);

    // The quality page and API say who is excluded; the audit log has the entries.
    let quality = as_admin(&server, &admin, Method::GET, QUALITY).await;
    assert_eq!(
        quality["exclusions"][0]["annotator"], "careless",
        "{quality}"
    );
    let (_, html) = lead.text("/admin/quality?dataset=mini").await;
    assert!(html.contains("Include careless"), "{html}");
    let (status, report) = lead.text("/admin/datasets/mini/report").await;
    assert_eq!(status, 200, "{report}");
    assert!(
        report.contains("answers on the 4 gold items")
            && report.contains("every answer of careless"),
        "the agreement report says what it leaves out: {report}"
    );
    let entries = audit_of(&hub, "annotator").await;
    assert!(
        entries
            .iter()
            .any(|e| e.action == "annotator.exclude" && e.target == "annotator careless"),
        "{entries:?}"
    );
    let gold_entries = audit_of(&hub, "gold.set").await;
    assert_eq!(gold_entries.len(), 1, "{gold_entries:?}");

    // Including them again brings their answers back, reversibly.
    as_admin(&server, &admin, Method::DELETE, exclusion).await;
    assert_eq!(human_row(&server).await["human"]["answers"], 32);
    server.stop().await;
}

#[tokio::test]
async fn gold_sets_refuse_bad_input_by_field_and_clearing_takes_unfinished_gold_out_of_queues() {
    let (server, records, admin) = server_with_items().await;
    let gold_path = "/api/v1/admin/datasets/mini/gold";
    for (body, says) in [
        (
            json!({"rate": 1, "share": 0.2}),
            "rate: \"1\" is not a whole number from 2 to 1000",
        ),
        (
            json!({"rate": 5, "share": 1.5}),
            "share: \"1.5\" is not a number above 0 and below 1",
        ),
        (json!({"rate": 5}), "give exactly one of share, items"),
        (
            json!({"rate": 5, "items": ["nope"]}),
            "not in dataset 'mini': nope",
        ),
        (json!({"rate": 5, "items": ["a", "a"]}), "line 2"),
    ] {
        let r = server
            .call(Method::PUT, gold_path)
            .bearer(&admin)
            .json(&body)
            .expect(400)
            .await;
        assert!(r.error().contains(says), "{body}: {}", r.error());
    }
    let none = as_admin(&server, &admin, Method::GET, gold_path).await;
    assert_eq!(none["gold"], Value::Null);
    server.call(Method::PUT, gold_path).expect(401).await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    server
        .call(Method::GET, gold_path)
        .bearer(&submitter)
        .expect(403)
        .await;

    // A seeded share: the same seed draws the same items.
    let mut drawn = Vec::new();
    for _ in 0..2 {
        drawn.push(
            server
                .call(Method::PUT, gold_path)
                .bearer(&admin)
                .json(&json!({"rate": 3, "share": 0.25, "seed": 11}))
                .expect(200)
                .await
                .json(),
        );
    }
    let first = &drawn[0];
    assert_eq!(first["gold"]["items"], drawn[1]["gold"]["items"]);
    assert_eq!(first["gold"]["items"].as_array().expect("items").len(), 6);
    let gold: HashSet<String> = first["gold"]["items"]
        .as_array()
        .expect("items")
        .iter()
        .map(|v| v.as_str().expect("id").to_owned())
        .collect();

    // A balanced split hands out only ordinary items; the mix adds gold at 1 in 3.
    let hub = Hub::from(server.pool.clone());
    let who = annotator(&server, "ann", false).await;
    annotation::assign(&hub, &tester(), "mini", &Assignment::Split(vec![who]))
        .await
        .expect("split");
    let queue = annotation::queue(&hub, who).await.expect("queue");
    let golden = queue.iter().filter(|e| gold.contains(&e.item_id)).count();
    assert_eq!(queue.len() - golden, records.len() - gold.len());
    assert_eq!(
        golden, 6,
        "18 ordinary items call for 9 gold ones; there are 6"
    );

    let cleared = as_admin(&server, &admin, Method::DELETE, gold_path).await;
    assert_eq!(cleared["removed"], 6);
    let queue = annotation::queue(&hub, who).await.expect("queue");
    assert_eq!(queue.len(), 18);
    let again = as_admin(&server, &admin, Method::DELETE, gold_path).await;
    assert_eq!(again["cleared"], false);
    server
        .call(Method::GET, "/api/v1/admin/datasets/nope/gold")
        .bearer(&admin)
        .expect(404)
        .await;
    server.stop().await;
}

/// The tags and attribute names of an HTML page, in order: its shape without its content.
fn shape(html: &str) -> Vec<String> {
    let mut shape = Vec::new();
    let mut rest = html;
    while let Some(start) = rest.find('<') {
        let after = &rest[start + 1..];
        let end = after.find('>').unwrap_or(after.len());
        let tag = &after[..end];
        let mut words = tag.split_whitespace();
        let name = words.next().unwrap_or("").to_owned();
        let attributes: Vec<String> = words
            .filter_map(|w| w.split('=').next())
            .filter(|a| !a.is_empty() && !a.starts_with('"'))
            .map(str::to_owned)
            .collect();
        shape.push(format!("{name} {}", attributes.join(" ")));
        rest = &after[end.min(after.len())..];
    }
    shape
}

#[tokio::test]
async fn a_gold_item_s_page_has_the_markup_of_any_other_item_of_its_kind() {
    let (server, records, admin) = server_with_items().await;
    // Items 0 and 1 are forward items of the same L: the first is made gold.
    let (gold_item, plain_item) = (id(&records[0]), id(&records[1]));
    server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/gold")
        .bearer(&admin)
        .json(&json!({"rate": 2, "items": [gold_item]}))
        .expect(200)
        .await;
    let who = annotator(&server, "ann", false).await;
    let hub = Hub::from(server.pool.clone());
    assign_listed(&hub, who, std::slice::from_ref(&plain_item)).await;
    let (mut ann, _) = logged_in_on(&server, "ann", "/annotate").await;
    let (_, queue) = ann.text("/annotate").await;
    assert!(
        queue.contains(&gold_item),
        "the gold item is in the queue: {queue}"
    );
    let (gold_status, gold_page) = ann.text(&format!("/annotate/mini/{gold_item}")).await;
    let (plain_status, plain_page) = ann.text(&format!("/annotate/mini/{plain_item}")).await;
    assert_eq!((gold_status.as_u16(), plain_status.as_u16()), (200, 200));
    assert_eq!(shape(&gold_page), shape(&plain_page));
    for page in [&gold_page, &plain_page, &queue] {
        assert!(!page.to_lowercase().contains("gold"), "{page}");
    }
    server.stop().await;
}

/// Runs `enact-hub` with `args`: success, standard output, standard error.
fn run(args: &[&str]) -> (bool, String, String) {
    let out = enact_hub().args(args).output().expect("enact-hub runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[tokio::test]
async fn the_command_line_sets_shows_and_clears_gold_and_excludes_annotators() {
    let (server, records, _) = server_with_items().await;
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let list = server.dir().join("gold.txt");
    std::fs::write(
        &list,
        format!(
            "# two gold items\n{}\n\n{}\n",
            id(&records[0]),
            id(&records[7])
        ),
    )
    .expect("list written");
    let list = list.to_str().expect("utf-8 path");

    let (ok, _, err) = run(&[
        "gold", "set", "mini", "--db", db, "--share", "1.5", "--rate", "5",
    ]);
    assert!(!ok && err.contains("--share"), "{err}");
    let (ok, _, err) = run(&[
        "gold", "set", "mini", "--db", db, "--items", list, "--rate", "1",
    ]);
    assert!(!ok && err.contains("--rate"), "{err}");
    let (ok, out, err) = run(&[
        "gold", "set", "mini", "--db", db, "--items", list, "--rate", "5",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("2 gold items, one in every 5"), "{out}");
    let (ok, out, _) = run(&["gold", "show", "mini", "--db", db]);
    assert!(
        ok && out.contains(&id(&records[7])) && out.contains("a list of items"),
        "{out}"
    );

    // `annotator VERB NAME` on "mini".
    let on_mini =
        |verb: &str, name: &str| run(&["annotator", verb, name, "--db", db, "--dataset", "mini"]);
    let (ok, _, err) = on_mini("exclude", "nobody");
    assert!(!ok && err.contains("no annotator named 'nobody'"), "{err}");
    annotator(&server, "ann", false).await;
    let (ok, out, err) = on_mini("exclude", "ann");
    assert!(
        ok && out.contains("left out of the Human row"),
        "{out}{err}"
    );
    let (ok, out, _) = on_mini("exclude", "ann");
    assert!(ok && out.contains("already"), "{out}");
    let (ok, out, err) = run(&[
        "annotator",
        "quality",
        "--db",
        db,
        "--dataset",
        "mini",
        "--json",
    ]);
    assert!(ok, "{err}");
    let report: Value = serde_json::from_str(&out).expect("JSON");
    assert_eq!(report["exclusions"][0]["annotator"], "ann", "{report}");
    assert_eq!(report["gold_items"], 2);
    let (ok, out, _) = run(&["annotator", "quality", "--db", db, "--dataset", "mini"]);
    assert!(ok && out.contains("excluded: ann"), "{out}");
    let (ok, _, err) = on_mini("include", "ann");
    assert!(ok, "{err}");

    let (ok, out, _) = run(&["gold", "clear", "mini", "--db", db]);
    assert!(ok && out.contains("gold set cleared"), "{out}");
    let (ok, out, _) = run(&["gold", "show", "mini", "--db", db]);
    assert!(ok && out.contains("has no gold set"), "{out}");
    let actions: Vec<String> = db!(
        server.pool,
        fetch_all,
        sqlx::query_scalar::<_, String>(
            "SELECT action FROM audit_log WHERE action LIKE 'gold.%' OR action LIKE 'annotator.%' \
             ORDER BY id"
        )
    )
    .expect("audit");
    assert_eq!(
        actions,
        [
            "gold.set",
            "annotator.exclude",
            "annotator.include",
            "gold.clear"
        ]
    );
    server.stop().await;
}

/// Polls `name`'s Human row on the running server until `holds` says yes, for at most two
/// seconds after the command that changed it returned: how long it took, or a failure naming
/// the last row seen.
async fn human_row_within_two_seconds(
    server: &TestServer,
    what: &str,
    holds: impl Fn(&Value) -> bool,
) -> std::time::Duration {
    let since = std::time::Instant::now();
    loop {
        let row = human_row(server).await;
        if holds(&row) {
            return since.elapsed();
        }
        assert!(
            since.elapsed() < std::time::Duration::from_secs(2),
            "{what}: the running server still shows {row} after 2 s"
        );
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_command_line_s_exclusions_and_gold_reach_a_running_server_within_two_seconds() {
    // The server caches its leaderboard; a command-line process beside it announces what it
    // changed through the database (SQLite's change feed, PostgreSQL's NOTIFY), and the
    // server drops the board within a poll.
    let (server, records, _) = server_with_items().await;
    let db = server.db_path();
    let db = db.to_str().expect("utf-8 path");
    let gts: BTreeMap<String, Vec<u8>> = records
        .iter()
        .map(|r| (id(r), labels(&r["gt_answer"])))
        .collect();
    let ordinary: Vec<String> = records.iter().map(id).take(8).collect();
    let hub = Hub::from(server.pool.clone());
    let careful = annotator(&server, "careful", false).await;
    let careless = annotator(&server, "careless", false).await;
    for who in [careful, careless] {
        assign_listed(&hub, who, &ordinary).await;
    }
    work_careful_and_careless(&server, careful, careless, &gts).await;
    let row = human_row(&server).await;
    assert_eq!(row["human"]["annotators"], 2, "{row}");

    // The board is cached: a change written to the database without an announcement (as no
    // use case writes one) is not seen, so what follows is the announcement's doing.
    db!(
        server.pool,
        execute,
        sqlx::query(
            "INSERT INTO annotator_exclusions (dataset, annotator, excluded_by) \
             SELECT id, $1, 'test' FROM datasets WHERE name = 'mini'"
        )
        .bind(careless)
    )
    .expect("excluded behind the server's back");
    tokio::time::sleep(std::time::Duration::from_millis(1500)).await;
    let row = human_row(&server).await;
    assert_eq!(
        row["human"]["annotators"], 2,
        "the server's board is cached, so an unannounced change stays unseen: {row}"
    );
    db!(
        server.pool,
        execute,
        sqlx::query("DELETE FROM annotator_exclusions WHERE annotator = $1").bind(careless)
    )
    .expect("exclusion undone");

    let on_mini =
        |verb: &str, name: &str| run(&["annotator", verb, name, "--db", db, "--dataset", "mini"]);
    let (ok, out, err) = on_mini("exclude", "careless");
    assert!(
        ok && out.contains("left out of the Human row"),
        "{out}{err}"
    );
    let took = human_row_within_two_seconds(&server, "annotator exclude", |row| {
        row["human"]["annotators"] == 1 && row["human"]["excluded_annotators"] == 1
    })
    .await;
    eprintln!("annotator exclude reached the running server in {took:?}");

    let (ok, out, err) = on_mini("include", "careless");
    assert!(ok, "{out}{err}");
    human_row_within_two_seconds(&server, "annotator include", |row| {
        row["human"]["annotators"] == 2 && row["human"]["excluded_annotators"] == 0
    })
    .await;

    // Gold items set from the command line leave the Human row at once too.
    let list = server.dir().join("gold.txt");
    std::fs::write(&list, format!("{}\n", ordinary[0])).expect("list written");
    let (ok, out, err) = run(&[
        "gold",
        "set",
        "mini",
        "--db",
        db,
        "--items",
        list.to_str().expect("utf-8 path"),
        "--rate",
        "5",
    ]);
    assert!(ok, "{out}{err}");
    human_row_within_two_seconds(&server, "gold set", |row| row["human"]["gold_items"] == 1).await;
    server.stop().await;
}

/// Found by scripts/schemathesis.sh: `fast_seconds` was documented as any string (an empty
/// one drew a 400), the gold body's fields had no ranges (an empty item id drew a 400), and a
/// `rate` of `5.0`, an integer to JSON Schema, was refused with 422. The document now states
/// what the handlers accept, and a whole float is a rate.
#[tokio::test]
async fn quality_and_gold_parameters_are_documented_as_the_handlers_read_them() {
    let (server, records, admin) = server_with_items().await;
    let doc = server
        .call(Method::GET, "/api/v1/openapi.json")
        .expect(200)
        .await
        .json();
    let fast = doc["paths"]["/api/v1/admin/annotators/quality"]["get"]["parameters"]
        .as_array()
        .and_then(|ps| ps.iter().find(|p| p["name"] == "fast_seconds"))
        .expect("fast_seconds is documented");
    assert_eq!(fast["schema"]["type"], "number", "{fast}");
    assert_eq!(fast["schema"]["exclusiveMinimum"], 0, "{fast}");
    let gold = &doc["components"]["schemas"]["GoldRequest"]["properties"];
    assert_eq!(gold["rate"]["minimum"], 2, "{gold}");
    assert_eq!(gold["rate"]["maximum"], 1000, "{gold}");
    assert_eq!(gold["share"]["exclusiveMaximum"], 1, "{gold}");
    assert_eq!(gold["items"]["minItems"], 1, "{gold}");
    assert_eq!(gold["items"]["uniqueItems"], true, "{gold}");
    assert!(gold["items"]["items"]["pattern"].is_string(), "{gold}");

    let set = server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/gold")
        .bearer(&admin)
        .json(&json!({"rate": 5.0, "items": [id(&records[0])]}))
        .expect(200)
        .await
        .json();
    assert_eq!(set["gold"]["rate"], 5);
    let refused = server
        .call(Method::PUT, "/api/v1/admin/datasets/mini/gold")
        .bearer(&admin)
        .json(&json!({"rate": 5.5, "items": [id(&records[0])]}))
        .expect(422)
        .await;
    assert!(refused.error().contains("rate"), "{}", refused.error());
    // A seed sent as a whole float (schemathesis sent one and got 422) draws as the integer.
    let mut drawn = Vec::new();
    for seed in [json!(11), json!(11.0)] {
        let set = server
            .call(Method::PUT, "/api/v1/admin/datasets/mini/gold")
            .bearer(&admin)
            .json(&json!({"rate": 3, "share": 0.25, "seed": seed}))
            .expect(200)
            .await
            .json();
        drawn.push(set["gold"]["items"].clone());
    }
    assert_eq!(drawn[0], drawn[1]);
    server.stop().await;
}
