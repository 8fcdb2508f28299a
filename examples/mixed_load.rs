//! A mixed load on a running enact-hub, for `scripts/load-mixed.sh` and BENCHMARKS.md.
//!
//! `mixed_load setup --db DB --dataset NAME` (server stopped) creates 50 annotators with
//! passwords, splits the dataset over their queues and issues 10 submitter tokens, writing
//! the accounts to a JSON file. `mixed_load run --base URL --accounts FILE` then plays, for
//! `--seconds`:
//! - annotators: log in, open their next item, save one or two drafts, submit (one in ten
//!   flagged instead), repeat;
//! - submitters: POST a full-size submission (every item of the dataset), pause, repeat;
//! - readers: the leaderboard page and JSON, item lists, item JSON and frames.
//!
//! It prints requests, throughput and p50/p99/max latency per route, and fails when any reply
//! is a 5xx or mentions `database is locked`. With `--window FILE` (two lines: the Unix time in
//! milliseconds something began, then when it ended, e.g. an import the script runs midway) it
//! prints the same table again for the requests sent in that window.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use enact_hub::app::annotation::Assignment;
use enact_hub::app::{self, Hub};
use enact_hub::core::audit::Actor;
use enact_hub::core::credentials::Role;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use reqwest::header::{COOKIE, LOCATION, SET_COOKIE};
use serde_json::{Value, json};

const PASSWORD: &str = "mixed load password";

/// One request: when it was sent (Unix milliseconds), how long it took (µs) and its status
/// (0: no reply).
#[derive(Clone, Copy)]
struct Timed {
    sent_ms: u64,
    micros: u64,
    status: u16,
}

/// Latencies and statuses per route, shared by every simulated client.
#[derive(Default)]
struct Stats {
    routes: BTreeMap<&'static str, Vec<Timed>>,
    statuses: BTreeMap<(&'static str, u16), u64>,
    locked: u64,
    failures: Vec<String>,
}

#[derive(Clone)]
struct Load {
    client: reqwest::Client,
    base: String,
    stats: Arc<Mutex<Stats>>,
    deadline: Instant,
}

/// A reply as the clients need it.
struct Reply {
    status: u16,
    location: Option<String>,
    cookies: Vec<String>,
    text: String,
}

impl Load {
    fn running(&self) -> bool {
        Instant::now() < self.deadline
    }

    /// Sends `request`, times it until the whole body is read, and records it under `route`.
    async fn send(&self, route: &'static str, request: reqwest::RequestBuilder) -> Option<Reply> {
        let started = Instant::now();
        let sent_ms = unix_ms();
        let result = request.send().await;
        let reply = match result {
            Ok(r) => {
                let status = r.status().as_u16();
                let location = r
                    .headers()
                    .get(LOCATION)
                    .and_then(|v| v.to_str().ok())
                    .map(str::to_owned);
                let cookies = r
                    .headers()
                    .get_all(SET_COOKIE)
                    .iter()
                    .filter_map(|v| v.to_str().ok())
                    .filter_map(|v| v.split(';').next())
                    .map(str::to_owned)
                    .collect();
                let text = r.text().await.unwrap_or_default();
                Some(Reply {
                    status,
                    location,
                    cookies,
                    text,
                })
            }
            Err(e) => {
                self.stats
                    .lock()
                    .unwrap()
                    .failures
                    .push(format!("{route}: {e}"));
                None
            }
        };
        let micros = started.elapsed().as_micros() as u64;
        let mut stats = self.stats.lock().unwrap();
        stats.routes.entry(route).or_default().push(Timed {
            sent_ms,
            micros,
            status: reply.as_ref().map_or(0, |r| r.status),
        });
        if let Some(r) = &reply {
            *stats.statuses.entry((route, r.status)).or_default() += 1;
            if r.text.contains("database is locked") {
                stats.locked += 1;
            }
            if r.status >= 500 {
                let text: String = r.text.chars().take(300).collect();
                stats
                    .failures
                    .push(format!("{route}: HTTP {}: {text}", r.status));
            }
        }
        reply
    }

    fn get(&self, path: &str) -> reqwest::RequestBuilder {
        self.client.get(format!("{}{path}", self.base))
    }

    fn post(&self, path: &str) -> reqwest::RequestBuilder {
        self.client.post(format!("{}{path}", self.base))
    }
}

fn csrf_of(html: &str) -> Option<String> {
    let start = html.find("name=\"csrf\" value=\"")? + 19;
    html.get(start..start + 64).map(str::to_owned)
}

async fn pause(rng: &mut ChaCha8Rng, millis: std::ops::Range<u64>) {
    tokio::time::sleep(Duration::from_millis(rng.random_range(millis))).await;
}

/// One annotator: log in, then next item, drafts, submit, until the time is up.
async fn annotator(load: Load, name: String, slots: Arc<BTreeMap<String, usize>>, seed: u64) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let Some(page) = load.send("GET /login", load.get("/login")).await else {
        return;
    };
    let (Some(token), Some(login_cookie)) = (csrf_of(&page.text), page.cookies.first()) else {
        return;
    };
    let form = [
        ("csrf", token.as_str()),
        ("name", &name),
        ("password", PASSWORD),
    ];
    let Some(login) = load
        .send(
            "POST /login",
            load.post("/login").header(COOKIE, login_cookie).form(&form),
        )
        .await
    else {
        return;
    };
    let Some(session) = login
        .cookies
        .iter()
        .find(|c| c.starts_with("enact_session="))
        .cloned()
    else {
        return;
    };
    let Some(queue) = load
        .send(
            "GET /annotate",
            load.get("/annotate").header(COOKIE, &session),
        )
        .await
    else {
        return;
    };
    let Some(csrf) = csrf_of(&queue.text) else {
        return;
    };
    while load.running() {
        let Some(next) = load
            .send(
                "GET /annotate/next",
                load.get("/annotate/next").header(COOKIE, &session),
            )
            .await
        else {
            return;
        };
        let Some(item_path) = next.location.filter(|l| l.starts_with("/annotate/demo/")) else {
            return; // queue done
        };
        let item = item_path.trim_start_matches("/annotate/demo/").to_owned();
        let Some(&n) = slots.get(&item) else { return };
        load.send(
            "GET /annotate/{dataset}/{item}",
            load.get(&item_path).header(COOKIE, &session),
        )
        .await;
        let mut answer: Vec<usize> = (1..=n).collect();
        answer.shuffle(&mut rng);
        let drafts = rng.random_range(1..=2);
        for d in 0..drafts {
            pause(&mut rng, 300..1500).await;
            let placed = (d + 1) * n / (drafts + 1);
            let draft: Vec<Value> = answer
                .iter()
                .enumerate()
                .map(|(i, l)| if i < placed { json!(l) } else { Value::Null })
                .collect();
            let body = json!({"slots": draft, "counts": {"placements": placed, "swaps": 0, "clears": 0, "undos": 0}});
            load.send(
                "POST /annotate/{dataset}/{item}/draft",
                load.post(&format!("{item_path}/draft"))
                    .header(COOKIE, &session)
                    .header("x-csrf-token", &csrf)
                    .json(&body),
            )
            .await;
        }
        pause(&mut rng, 300..1500).await;
        if rng.random_bool(0.1) {
            // Now and then an item is flagged instead (its write starts with a read).
            let form = [
                ("csrf", csrf.as_str()),
                ("reason", "unclear"),
                ("action", "flag"),
            ];
            load.send(
                "POST /annotate/{dataset}/{item}/skip",
                load.post(&format!("{item_path}/skip"))
                    .header(COOKIE, &session)
                    .form(&form),
            )
            .await;
            continue;
        }
        let body = json!({"slots": answer, "counts": {"placements": n, "swaps": 0, "clears": 0, "undos": 0}});
        load.send(
            "POST /annotate/{dataset}/{item}/submit",
            load.post(&format!("{item_path}/submit"))
                .header(COOKIE, &session)
                .header("x-csrf-token", &csrf)
                .json(&body),
        )
        .await;
    }
}

/// One submitter: a full-size submission, a pause, again.
async fn submitter(load: Load, index: usize, token: String, slots: Arc<BTreeMap<String, usize>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(1000 + index as u64);
    let mut n = 0;
    while load.running() {
        let body: String = slots
            .iter()
            .map(|(id, &k)| {
                let mut answer: Vec<usize> = (1..=k).collect();
                answer.shuffle(&mut rng);
                json!({"id": id, "answer": answer}).to_string() + "\n"
            })
            .collect();
        load.send(
            "POST /api/v1/datasets/{dataset}/submissions",
            load.post(&format!(
                "/api/v1/datasets/demo/submissions?model=load-{index}-{n}"
            ))
            .bearer_auth(&token)
            .body(body),
        )
        .await;
        n += 1;
        pause(&mut rng, 500..1500).await;
    }
}

/// One reader: public pages and JSON, item by item.
async fn reader(load: Load, index: usize, ids: Arc<Vec<String>>, frames: Arc<Vec<String>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(2000 + index as u64);
    while load.running() {
        match rng.random_range(0..6) {
            0 => {
                load.send("GET /leaderboard/{dataset}", load.get("/leaderboard/demo"))
                    .await;
            }
            1 => {
                load.send(
                    "GET /api/v1/datasets/{dataset}/leaderboard",
                    load.get("/api/v1/datasets/demo/leaderboard"),
                )
                .await;
            }
            2 => {
                let page = rng.random_range(1..=(ids.len() / 50).max(1));
                load.send(
                    "GET /api/v1/datasets/{dataset}/items",
                    load.get(&format!("/api/v1/datasets/demo/items?page={page}")),
                )
                .await;
            }
            3 => {
                let id = &ids[rng.random_range(0..ids.len())];
                load.send(
                    "GET /datasets/{dataset}/items/{item}",
                    load.get(&format!("/datasets/demo/items/{id}")),
                )
                .await;
            }
            4 => {
                let id = &ids[rng.random_range(0..ids.len())];
                load.send(
                    "GET /api/v1/datasets/{dataset}/items/{item}",
                    load.get(&format!("/api/v1/datasets/demo/items/{id}")),
                )
                .await;
            }
            _ => {
                let frame = &frames[rng.random_range(0..frames.len())];
                load.send("GET /api/v1/frames/{sha256}", load.get(frame))
                    .await;
            }
        }
        pause(&mut rng, 10..50).await;
    }
}

fn unix_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// The routes whose latencies count as an annotator's writes.
const ANNOTATOR_WRITES: [&str; 3] = [
    "POST /annotate/{dataset}/{item}/draft",
    "POST /annotate/{dataset}/{item}/submit",
    "POST /annotate/{dataset}/{item}/skip",
];

/// The routes whose latencies count as an annotator's pages.
const ANNOTATOR_PAGES: [&str; 3] = [
    "GET /annotate",
    "GET /annotate/next",
    "GET /annotate/{dataset}/{item}",
];

/// p50 / p99 / max in ms of the requests of `routes` sent from `from` (Unix ms) on, and how
/// many there were.
fn latencies(stats: &Stats, routes: &[&str], from: u64) -> (usize, f64, f64, f64) {
    let mut sorted: Vec<u64> = routes
        .iter()
        .filter_map(|r| stats.routes.get(r))
        .flatten()
        .filter(|t| t.sent_ms >= from)
        .map(|t| t.micros)
        .collect();
    if sorted.is_empty() {
        return (0, 0.0, 0.0, 0.0);
    }
    sorted.sort_unstable();
    (
        sorted.len(),
        percentile(&sorted, 0.5),
        percentile(&sorted, 0.99),
        percentile(&sorted, 1.0),
    )
}

/// The annotators' pages and writes together, over the whole run and once every annotator
/// has logged in: the 50 logins of the first seconds (each a password hash, CPU-heavy by
/// design) are a burst no steady state has.
fn print_annotator_lines(stats: &Stats, started_ms: u64) {
    let logged_in = stats
        .routes
        .get("POST /login")
        .into_iter()
        .flatten()
        .map(|t| t.sent_ms + t.micros / 1000)
        .max()
        .unwrap_or(0);
    for (what, from) in [
        ("the whole run".to_owned(), 0),
        (
            format!(
                "after the last login, from {:.1} s",
                logged_in.saturating_sub(started_ms) as f64 / 1000.0
            ),
            logged_in,
        ),
    ] {
        for (kind, routes) in [
            ("annotator pages (queue, next, item)", &ANNOTATOR_PAGES[..]),
            (
                "annotator writes (drafts, answers, flags)",
                &ANNOTATOR_WRITES[..],
            ),
        ] {
            let (n, p50, p99, max) = latencies(stats, routes, from);
            println!(
                "{kind}, {what}: {n} requests, p50 {p50:.1} ms, p99 {p99:.1} ms, max {max:.1} ms"
            );
        }
    }
}

/// The per-route table of the requests sent in `window` (Unix ms, inclusive), over `seconds`,
/// and a line for the annotators' writes together.
fn print_table(stats: &Stats, window: (u64, u64), seconds: f64) -> usize {
    println!(
        "| route | requests | req/s | p50 ms | p99 ms | p99.9 ms | max ms | statuses |\n|---|---|---|---|---|---|---|---|"
    );
    let in_window = |t: &&Timed| (window.0..=window.1).contains(&t.sent_ms);
    let mut total = 0;
    let mut writes = Vec::new();
    for (route, times) in &stats.routes {
        let sent: Vec<&Timed> = times.iter().filter(in_window).collect();
        if sent.is_empty() {
            continue;
        }
        let mut sorted: Vec<u64> = sent.iter().map(|t| t.micros).collect();
        sorted.sort_unstable();
        total += sorted.len();
        if ANNOTATOR_WRITES.contains(route) {
            writes.extend_from_slice(&sorted);
        }
        let mut by_status = BTreeMap::<u16, u64>::new();
        for t in &sent {
            *by_status.entry(t.status).or_default() += 1;
        }
        let statuses: Vec<String> = by_status.iter().map(|(s, n)| format!("{s}: {n}")).collect();
        println!(
            "| {route} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {} |",
            sorted.len(),
            sorted.len() as f64 / seconds,
            percentile(&sorted, 0.5),
            percentile(&sorted, 0.99),
            percentile(&sorted, 0.999),
            percentile(&sorted, 1.0),
            statuses.join(", ")
        );
    }
    if !writes.is_empty() {
        writes.sort_unstable();
        println!(
            "\nannotator writes (drafts, answers, flags): {} requests, p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
            writes.len(),
            percentile(&writes, 0.5),
            percentile(&writes, 0.99),
            percentile(&writes, 1.0)
        );
    }
    total
}

/// The `count` slowest reads of the run (GET requests; submissions and logins are slow by
/// their nature), each with when it was sent and what else was in flight meanwhile (requests
/// of each route whose time overlapped it): a reader's rare slow request is told apart as
/// waiting behind logins' password hashes, submissions' scoring, or its own route's work.
fn print_slowest(stats: &Stats, started_ms: u64, count: usize) {
    let all: Vec<(&'static str, Timed)> = stats
        .routes
        .iter()
        .flat_map(|(route, times)| times.iter().map(move |t| (*route, *t)))
        .collect();
    let mut reads: Vec<&(&'static str, Timed)> = all
        .iter()
        .filter(|(route, _)| route.starts_with("GET "))
        .collect();
    reads.sort_unstable_by_key(|(_, t)| std::cmp::Reverse(t.micros));
    println!("\nthe {count} slowest reads (sent at seconds from the start; in flight meanwhile):");
    for (route, slow) in reads.iter().take(count) {
        let (from, to) = (slow.sent_ms, slow.sent_ms + slow.micros / 1000);
        let mut overlapping = BTreeMap::<&str, usize>::new();
        for (other, t) in &all {
            if t.sent_ms <= to && t.sent_ms + t.micros / 1000 >= from {
                *overlapping.entry(*other).or_default() += 1;
            }
        }
        let mut busiest: Vec<(&str, usize)> = overlapping.into_iter().collect();
        busiest.sort_unstable_by_key(|(_, n)| std::cmp::Reverse(*n));
        let meanwhile: Vec<String> = busiest
            .iter()
            .take(4)
            .map(|(r, n)| format!("{n} × {r}"))
            .collect();
        println!(
            "- {route}: {:.0} ms, sent at {:.1} s, status {}; meanwhile {}",
            slow.micros as f64 / 1000.0,
            slow.sent_ms.saturating_sub(started_ms) as f64 / 1000.0,
            slow.status,
            meanwhile.join(", ")
        );
    }
}

fn percentile(sorted: &[u64], p: f64) -> f64 {
    let rank = ((p * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1] as f64 / 1000.0
}

async fn run(
    base: String,
    accounts: PathBuf,
    seconds: u64,
    window: Option<PathBuf>,
) -> anyhow::Result<bool> {
    let accounts: Value = serde_json::from_slice(&std::fs::read(&accounts)?)?;
    let client = reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .pool_max_idle_per_host(200)
        .build()?;
    // Every item's number of labels, and frame addresses for the readers.
    let mut slots = BTreeMap::new();
    let mut page = Some("/api/v1/datasets/demo/items?per_page=500".to_owned());
    while let Some(path) = page {
        let list: Value = client
            .get(format!("{base}{path}"))
            .send()
            .await?
            .json()
            .await?;
        for item in list["items"].as_array().into_iter().flatten() {
            let id = item["id"].as_str().unwrap_or_default().to_owned();
            let l = item["step_length"].as_u64().unwrap_or(3) as usize;
            slots.insert(id, l - 1);
        }
        page = list["next"].as_str().map(str::to_owned);
    }
    let ids: Vec<String> = slots.keys().cloned().collect();
    let mut frames = Vec::new();
    for id in ids.iter().take(64) {
        let item: Value = client
            .get(format!("{base}/api/v1/datasets/demo/items/{id}"))
            .send()
            .await?
            .json()
            .await?;
        for image in item["images"].as_array().into_iter().flatten() {
            frames.push(image["url"].as_str().unwrap_or_default().to_owned());
        }
    }
    eprintln!(
        "{} items, {} frames; running {seconds} s",
        slots.len(),
        frames.len()
    );
    let (slots, ids, frames) = (Arc::new(slots), Arc::new(ids), Arc::new(frames));
    let started = Instant::now();
    let started_ms = unix_ms();
    let load = Load {
        client,
        base,
        stats: Arc::default(),
        deadline: started + Duration::from_secs(seconds),
    };
    let mut tasks = Vec::new();
    for (i, name) in accounts["annotators"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
    {
        let name = name.as_str().unwrap_or_default().to_owned();
        tasks.push(tokio::spawn(annotator(
            load.clone(),
            name,
            slots.clone(),
            i as u64,
        )));
    }
    for (i, token) in accounts["tokens"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
    {
        let token = token.as_str().unwrap_or_default().to_owned();
        tasks.push(tokio::spawn(submitter(
            load.clone(),
            i,
            token,
            slots.clone(),
        )));
    }
    for i in 0..10 {
        tasks.push(tokio::spawn(reader(
            load.clone(),
            i,
            ids.clone(),
            frames.clone(),
        )));
    }
    for task in tasks {
        task.await?;
    }
    let elapsed = started.elapsed().as_secs_f64();
    let ended_ms = unix_ms();
    let stats = load.stats.lock().unwrap();
    let total = print_table(&stats, (0, u64::MAX), elapsed);
    let scored = stats
        .statuses
        .get(&("POST /api/v1/datasets/{dataset}/submissions", 201))
        .copied()
        .unwrap_or(0);
    println!(
        "submissions scored and stored: {scored} ({:.2}/s)",
        scored as f64 / elapsed
    );
    println!();
    print_annotator_lines(&stats, started_ms);
    print_slowest(&stats, started_ms, 15);
    let server_errors: u64 = stats
        .statuses
        .iter()
        .filter(|((_, s), _)| *s >= 500)
        .map(|(_, n)| n)
        .sum();
    println!(
        "\n{total} requests in {elapsed:.1} s ({:.0} req/s); 5xx: {server_errors}; \
         `database is locked` in a reply: {}; transport failures: {}",
        total as f64 / elapsed,
        stats.locked,
        stats.failures.len() as u64 - server_errors
    );
    for failure in stats.failures.iter().take(10) {
        eprintln!("failure: {failure}");
    }
    if let Some(window) = window {
        let text = std::fs::read_to_string(&window)?;
        let mut times = text.lines().filter_map(|l| l.trim().parse::<u64>().ok());
        let from = times
            .next()
            .ok_or_else(|| anyhow::anyhow!("{}: no start time", window.display()))?;
        let (to, note) = match times.next() {
            Some(to) => (to, ""),
            None => (ended_ms, " (it had not ended when the load did)"),
        };
        let seconds = to.saturating_sub(from) as f64 / 1000.0;
        println!(
            "\nrequests sent during the window of {}: {seconds:.1} s{note}",
            window.display()
        );
        print_table(&stats, (from, to), seconds.max(0.001));
    }
    Ok(stats.failures.is_empty() && stats.locked == 0)
}

async fn setup(db: PathBuf, dataset: String, out: PathBuf) -> anyhow::Result<()> {
    let hub = Hub::open(&db).await?;
    let operator = Actor::Operator("mixed-load".to_owned());
    let mut annotators = Vec::new();
    let mut ids = Vec::new();
    for i in 1..=50 {
        let name = format!("load{i:02}");
        let invited = app::annotators::create(&hub, &operator, &name, false).await?;
        ids.push(
            app::annotators::accept_invite(&hub, &invited.invite_token, PASSWORD, PASSWORD).await?,
        );
        annotators.push(name);
    }
    let assigned =
        app::annotation::assign(&hub, &operator, &dataset, &Assignment::Split(ids)).await?;
    let mut tokens = Vec::new();
    for i in 1..=10 {
        let created = app::tokens::issue(
            &hub,
            &operator,
            &format!("submitter{i:02}"),
            Role::Submitter,
            None,
            None,
        )
        .await?;
        tokens.push(created.token);
    }
    hub.close().await;
    std::fs::write(
        &out,
        serde_json::to_vec_pretty(&json!({"annotators": annotators, "tokens": tokens}))?,
    )?;
    eprintln!(
        "50 annotators ({} items assigned), 10 submitter tokens -> {}",
        assigned.added,
        out.display()
    );
    Ok(())
}

fn flag(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .cloned()
}

#[tokio::main]
async fn main() -> anyhow::Result<std::process::ExitCode> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: mixed_load setup --db DB --dataset NAME --out FILE | \
                 run --base URL --accounts FILE [--seconds 60] [--window FILE]";
    match args.get(1).map(String::as_str) {
        Some("setup") => {
            let (Some(db), Some(dataset), Some(out)) = (
                flag(&args, "--db"),
                flag(&args, "--dataset"),
                flag(&args, "--out"),
            ) else {
                anyhow::bail!("{usage}");
            };
            setup(db.into(), dataset, out.into()).await?;
            Ok(std::process::ExitCode::SUCCESS)
        }
        Some("run") => {
            let (Some(base), Some(accounts)) = (flag(&args, "--base"), flag(&args, "--accounts"))
            else {
                anyhow::bail!("{usage}");
            };
            let seconds = flag(&args, "--seconds").map_or(Ok(60), |s| s.parse())?;
            let window = flag(&args, "--window").map(PathBuf::from);
            let clean = run(base, accounts.into(), seconds, window).await?;
            Ok(if clean {
                std::process::ExitCode::SUCCESS
            } else {
                std::process::ExitCode::FAILURE
            })
        }
        _ => anyhow::bail!("{usage}"),
    }
}
