//! Human annotation over HTTP: invites and login, CSRF, blind annotation and 403s, drafts,
//! submissions scored like model answers, the admin page.

use enact_hub::core::credentials::{hash_password, random_token as new_token, token_hash};
use enact_hub::store;
use reqwest::StatusCode;
use reqwest::header::{COOKIE, SET_COOKIE};
use serde_json::{Value, json};

use enact_hub::store::Pool;
use enact_hub::web::WebConfig;

use crate::helpers::*;

/// A client that keeps its cookies by hand and does not follow redirects, so tests see the
/// `Set-Cookie` and `Location` headers.
pub struct Browser {
    client: reqwest::Client,
    base: String,
    cookies: Vec<(String, String)>,
    /// An `Authorization` header sent with every request (an API token on a page).
    authorization: Option<String>,
    /// An `X-Forwarded-For` header sent with every request (as a proxy would add).
    forwarded_for: Option<String>,
}

impl Browser {
    pub fn new(server: &TestServer) -> Browser {
        Browser::at(&server.url(""))
    }

    /// A browser for the server at `base` (`http://host:port`).
    pub fn at(base: &str) -> Browser {
        Browser {
            client: reqwest::Client::builder()
                .redirect(reqwest::redirect::Policy::none())
                .build()
                .expect("client"),
            base: base.to_owned(),
            cookies: Vec::new(),
            authorization: None,
            forwarded_for: None,
        }
    }

    /// Sends this browser's next requests, its cookies included, to the server at `base`.
    pub fn switch_to(&mut self, base: &str) {
        base.clone_into(&mut self.base);
    }

    /// Sends `Authorization: Bearer token` with every request, as an API client would.
    pub fn with_bearer(mut self, token: &str) -> Browser {
        self.authorization = Some(format!("Bearer {token}"));
        self
    }

    /// Sends `X-Forwarded-For: client` with every request, as a reverse proxy would.
    pub fn forwarded_for(mut self, client: &str) -> Browser {
        self.forwarded_for = Some(client.to_owned());
        self
    }

    /// Reads the pages in `language` (`zh-CN`), as the language menu's cookie chooses it.
    pub fn in_language(mut self, language: &str) -> Browser {
        self.cookies
            .push(("enact_lang".to_owned(), language.to_owned()));
        self
    }

    fn request(&self, method: reqwest::Method, path: &str) -> reqwest::RequestBuilder {
        let mut request = self
            .client
            .request(method, format!("{}{path}", self.base))
            .header(COOKIE, self.cookie_header());
        if let Some(value) = &self.authorization {
            request = request.header("authorization", value);
        }
        if let Some(client) = &self.forwarded_for {
            request = request.header("x-forwarded-for", client);
        }
        request
    }

    /// The `Cookie` header this browser sends.
    pub fn cookie_header(&self) -> String {
        self.cookies
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join("; ")
    }

    fn keep_cookies(&mut self, response: &reqwest::Response) {
        for value in response.headers().get_all(SET_COOKIE) {
            let text = value.to_str().expect("ascii cookie");
            let (pair, _) = text.split_once(';').unwrap_or((text, ""));
            let (k, v) = pair.split_once('=').expect("name=value");
            self.cookies.retain(|(name, _)| name != k);
            if !v.is_empty() {
                self.cookies.push((k.to_owned(), v.to_owned()));
            }
        }
    }

    pub async fn get(&mut self, path: &str) -> reqwest::Response {
        let r = self
            .request(reqwest::Method::GET, path)
            .send()
            .await
            .unwrap_or_else(|e| panic!("GET {path}: {e}"));
        self.keep_cookies(&r);
        r
    }

    pub async fn text(&mut self, path: &str) -> (StatusCode, String) {
        let r = self.get(path).await;
        (r.status(), r.text().await.expect("body"))
    }

    pub async fn post_form(&mut self, path: &str, fields: &[(&str, &str)]) -> reqwest::Response {
        let r = self
            .request(reqwest::Method::POST, path)
            .header("content-type", "application/x-www-form-urlencoded")
            .body(serde_urlencoded::to_string(fields).expect("form"))
            .send()
            .await
            .unwrap_or_else(|e| panic!("POST {path}: {e}"));
        self.keep_cookies(&r);
        r
    }

    pub async fn post_json(
        &mut self,
        path: &str,
        csrf: Option<&str>,
        body: &Value,
    ) -> reqwest::Response {
        let mut request = self.request(reqwest::Method::POST, path).json(body);
        if let Some(token) = csrf {
            request = request.header("x-csrf-token", token);
        }
        let r = request
            .send()
            .await
            .unwrap_or_else(|e| panic!("POST {path}: {e}"));
        self.keep_cookies(&r);
        r
    }

    /// The CSRF token a page carries in its forms.
    pub async fn csrf(&mut self, path: &str) -> String {
        let (status, html) = self.text(path).await;
        assert_eq!(status, StatusCode::OK, "{path}: {html}");
        hidden_csrf(&html)
    }

    pub async fn login(&mut self, name: &str, password: &str) -> reqwest::Response {
        let token = self.csrf("/login").await;
        self.post_form(
            "/login",
            &[("csrf", &token), ("name", name), ("password", password)],
        )
        .await
    }
}

/// The files of `/admin/datasets/{dataset}/report.tar{query}` as (path, text), read as `admin`.
pub async fn report_bundle(
    admin: &mut Browser,
    dataset: &str,
    query: &str,
) -> Vec<(String, String)> {
    let bytes = admin
        .get(&format!("/admin/datasets/{dataset}/report.tar{query}"))
        .await
        .bytes()
        .await
        .expect("tar");
    let mut archive = tar::Archive::new(bytes.as_ref());
    let mut files = Vec::new();
    for entry in archive.entries().expect("entries") {
        let mut entry = entry.expect("entry");
        let path = entry.path().expect("path").display().to_string();
        let mut text = String::new();
        std::io::Read::read_to_string(&mut entry, &mut text).expect("utf-8");
        files.push((path, text));
    }
    files
}

pub fn hidden_csrf(html: &str) -> String {
    let start = html.find("name=\"csrf\" value=\"").expect("a csrf field") + 19;
    html[start..start + 64].to_owned()
}

pub const PASSWORD: &str = "a long enough password";

/// Creates an account with a password already set; returns its id.
pub async fn annotator(server: &TestServer, name: &str, admin: bool) -> i64 {
    annotator_on(&server.pool, name, admin).await
}

/// [`annotator`] in the database `pool`.
pub async fn annotator_on(pool: &Pool, name: &str, admin: bool) -> i64 {
    let mut tx = write_tx(pool).await;
    let id = store::annotations::create_annotator(&mut tx, name, admin, &token_hash(&new_token()))
        .await
        .expect("insert");
    tx.commit().await.expect("commit");
    let hash = hash_password(PASSWORD).expect("hash");
    db!(
        pool,
        execute,
        sqlx::query("UPDATE annotators SET password_hash = $1, invite_hash = NULL WHERE id = $2")
            .bind(&hash)
            .bind(id)
    )
    .expect("set password");
    id
}

/// Assigns the listed items of dataset "mini" to `annotator`.
pub async fn assign(server: &TestServer, annotator: i64, item_ids: &[&str]) {
    assign_in(server, "mini", annotator, item_ids).await;
}

/// Appends items of `dataset` to an annotator's queue.
pub async fn assign_in(server: &TestServer, dataset: &str, annotator: i64, item_ids: &[&str]) {
    assign_on(&server.pool, dataset, annotator, item_ids).await;
}

/// [`assign_in`] in the database `pool`.
pub async fn assign_on(pool: &Pool, dataset: &str, annotator: i64, item_ids: &[&str]) {
    let mut conn = pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, dataset)
        .await
        .expect("query")
        .expect("dataset");
    let ids: Vec<String> = item_ids.iter().map(|s| (*s).to_owned()).collect();
    let rows = store::annotations::item_rowids(&mut conn, dataset.id, &ids)
        .await
        .expect("query")
        .into_iter()
        .collect::<Option<Vec<i64>>>()
        .expect("known ids");
    drop(conn);
    let pairs: Vec<(i64, i64)> = rows.into_iter().map(|r| (annotator, r)).collect();
    let mut tx = write_tx(pool).await;
    store::annotations::assign(&mut tx, &pairs)
        .await
        .expect("assign");
    tx.commit().await.expect("commit");
}

async fn logged_in(server: &TestServer, name: &str) -> (Browser, String) {
    logged_in_on(server, name, "/annotate").await
}

/// `name` logged in with the test password, and the CSRF token of `page`.
pub async fn logged_in_on(server: &TestServer, name: &str, page: &str) -> (Browser, String) {
    let mut browser = Browser::new(server);
    let r = browser.login(name, PASSWORD).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER, "login of {name}");
    let csrf = browser.csrf(page).await;
    (browser, csrf)
}

/// Annotator "alice", every item of `records` assigned to her, logged in: her browser, its
/// CSRF token, and the item ids in order.
async fn alice_with_every_item(
    server: &TestServer,
    records: &[Value],
) -> (Browser, String, Vec<String>) {
    let a = annotator(server, "alice", false).await;
    let ids: Vec<String> = (0..records.len()).map(|i| id(records, i)).collect();
    let refs: Vec<&str> = ids.iter().map(String::as_str).collect();
    assign(server, a, &refs).await;
    let (alice, csrf) = logged_in(server, "alice").await;
    (alice, csrf, ids)
}

fn id(records: &[Value], i: usize) -> String {
    records[i]["id"].as_str().expect("id").to_owned()
}

#[tokio::test]
async fn invite_sets_a_password_once_and_logs_in() {
    let (server, _) = spawn_app_with_release().await;
    let token = new_token();
    {
        let mut tx = write_tx(&server.pool).await;
        store::annotations::create_annotator(&mut tx, "ada", false, &token_hash(&token))
            .await
            .expect("insert");
        tx.commit().await.expect("commit");
    }
    let mut browser = Browser::new(&server);
    let path = format!("/invite/{token}");
    let csrf = browser.csrf(&path).await;
    let short = browser
        .post_form(
            &path,
            &[("csrf", &csrf), ("password", "short"), ("repeat", "short")],
        )
        .await;
    assert_eq!(short.status(), StatusCode::BAD_REQUEST);
    assert!(
        short
            .text()
            .await
            .expect("body")
            .contains("use at least 10")
    );
    let csrf = browser.csrf(&path).await;
    let ok = browser
        .post_form(
            &path,
            &[
                ("csrf", &csrf),
                ("password", PASSWORD),
                ("repeat", PASSWORD),
            ],
        )
        .await;
    assert_eq!(ok.status(), StatusCode::SEE_OTHER);
    let cookie = ok
        .headers()
        .get_all(SET_COOKIE)
        .iter()
        .map(|v| v.to_str().expect("ascii").to_owned())
        .find(|c| c.starts_with("enact_session="))
        .expect("a session cookie");
    assert!(
        cookie.contains("HttpOnly") && cookie.contains("SameSite=Strict"),
        "{cookie}"
    );
    assert!(!cookie.contains("Secure"), "plain HTTP: {cookie}");
    let (status, html) = browser.text("/annotate").await;
    assert_eq!(status, StatusCode::OK);
    assert!(html.contains("Logged in as <strong>ada</strong>"), "{html}");
    // The link works once.
    let (status, html) = Browser::new(&server).text(&path).await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(html.contains("already been used"), "{html}");
    // Behind a TLS proxy the cookie is Secure.
    let r = reqwest::Client::new()
        .get(server.url("/login"))
        .header("x-forwarded-proto", "https")
        .send()
        .await
        .expect("login page");
    let cookie = r
        .headers()
        .get(SET_COOKIE)
        .expect("cookie")
        .to_str()
        .expect("ascii");
    assert!(cookie.contains("; Secure"), "{cookie}");
    server.stop().await;
}

#[tokio::test]
async fn logins_are_rate_limited_per_account_with_a_clear_message() {
    let (server, _) = spawn_app_with_release().await;
    annotator(&server, "bob", false).await;
    let mut browser = Browser::new(&server);
    for _ in 0..5 {
        let r = browser.login("bob", "wrong password!").await;
        assert_eq!(r.status(), StatusCode::UNAUTHORIZED);
        assert!(
            r.text()
                .await
                .expect("body")
                .contains("unknown name or wrong password")
        );
    }
    // Even the right password is refused now, and the page says why and for how long.
    let r = browser.login("bob", PASSWORD).await;
    assert_eq!(r.status(), StatusCode::TOO_MANY_REQUESTS);
    let retry_after: u64 = r.headers()["retry-after"]
        .to_str()
        .expect("ascii")
        .parse()
        .expect("seconds");
    assert!(
        (14 * 60..=15 * 60).contains(&retry_after),
        "Retry-After: {retry_after}"
    );
    let html = r.text().await.expect("body");
    assert!(
        html.contains("too many failed logins for account &#39;bob&#39;")
            && html.contains("try again in 15 minutes"),
        "{html}"
    );
    // Unauthenticated pages redirect to the login form; scripts get 401.
    let r = Browser::new(&server).get("/annotate").await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert_eq!(r.headers()["location"], "/login");
    let r = Browser::new(&server)
        .post_json("/annotate/mini/x/draft", Some("t"), &json!({}))
        .await;
    assert_eq!(r.status(), StatusCode::UNAUTHORIZED);
    server.stop().await;
}

/// Twenty failed logins from `client` (as `X-Forwarded-For`), each on its own unknown name so
/// that no account's limit is reached.
async fn fail_logins_from(server: &TestServer, client: impl Fn(usize) -> String) {
    for k in 0..20 {
        let r = Browser::new(server)
            .forwarded_for(&client(k))
            .login(&format!("nobody{k}"), "wrong password!")
            .await;
        assert_eq!(r.status(), StatusCode::UNAUTHORIZED, "attempt {k}");
    }
}

/// A server that trusts 127.0.0.1, where the test's requests come from, as its proxy, with
/// annotator bob.
async fn behind_a_trusted_proxy() -> TestServer {
    let config = WebConfig {
        trusted_proxies: vec!["127.0.0.1".parse().expect("address")],
        ..WebConfig::default()
    };
    let server = spawn_app_configured(config, |_, _| async {}).await;
    annotator(&server, "bob", false).await;
    server
}

#[tokio::test]
async fn behind_a_trusted_proxy_the_address_limit_counts_each_client() {
    let server = behind_a_trusted_proxy().await;
    fail_logins_from(&server, |_| "203.0.113.5".to_owned()).await;
    // That client is blocked, with the reason ...
    let r = Browser::new(&server)
        .forwarded_for("203.0.113.5")
        .login("bob", PASSWORD)
        .await;
    assert_eq!(r.status(), StatusCode::TOO_MANY_REQUESTS);
    let html = r.text().await.expect("body");
    assert!(
        html.contains("too many failed logins for your address"),
        "{html}"
    );
    // ... and no one else behind the same proxy is.
    let r = Browser::new(&server)
        .forwarded_for("198.51.100.7")
        .login("bob", PASSWORD)
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    server.stop().await;
}

#[tokio::test]
async fn ipv6_clients_count_by_their_64_network() {
    let server = behind_a_trusted_proxy().await;
    // A fresh address of one /64 for every attempt ...
    fail_logins_from(&server, |k| format!("2001:db8:1:2::{:x}", k + 1)).await;
    // ... is still one client: another address of that network is blocked,
    let r = Browser::new(&server)
        .forwarded_for("2001:db8:1:2:ffff::9")
        .login("bob", PASSWORD)
        .await;
    assert_eq!(r.status(), StatusCode::TOO_MANY_REQUESTS);
    assert!(r.headers().contains_key("retry-after"));
    // while the next network is not.
    let r = Browser::new(&server)
        .forwarded_for("2001:db8:1:3::1")
        .login("bob", PASSWORD)
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    server.stop().await;
}

/// The median of `times`.
fn median(mut times: Vec<std::time::Duration>) -> std::time::Duration {
    times.sort();
    times[times.len() / 2]
}

#[tokio::test]
async fn an_unknown_name_takes_as_long_to_refuse_as_a_wrong_password() {
    use enact_hub::app::{Hub, annotators};
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().expect("temporary directory");
    let pool = fresh_db(&dir).await;
    let hub = Hub::from(pool.clone());
    annotator_on(&pool, "bob", false).await;
    // Invited, no password yet.
    annotators::create(&hub, &tester(), "carol", false)
        .await
        .expect("invite");
    annotators::prepare_login().await.expect("the dummy hash");
    // Interleaved, so that whatever else the machine does falls on all three alike.
    const TRIES: usize = 25;
    let kinds = [
        ("a wrong password for a real name", "bob"),
        ("an unknown name", "nobody-by-this-name"),
        ("a name whose invite is unused", "carol"),
    ];
    let mut times: Vec<Vec<Duration>> = vec![Vec::new(); kinds.len()];
    for _ in 0..TRIES {
        for (k, (_, name)) in kinds.iter().enumerate() {
            let started = Instant::now();
            let found = annotators::check_password(&hub, name, "wrong password!")
                .await
                .expect("check");
            times[k].push(started.elapsed());
            assert_eq!(found, None);
        }
    }
    // Both sides hash once; without that an unknown name is answered over a hundred times
    // faster. Medians of 25 tries are steady to well within a factor of 1.5 on a loaded
    // machine (the hash is tens of milliseconds of CPU, a database lookup well under one).
    let medians: Vec<Duration> = times.into_iter().map(median).collect();
    let wrong = medians[0];
    for ((what, _), median) in kinds.iter().zip(&medians).skip(1) {
        let ratio = median.as_secs_f64() / wrong.as_secs_f64();
        assert!(
            (1.0 / 1.5..=1.5).contains(&ratio),
            "{what}: median {median:?} against {wrong:?} for a wrong password (ratio {ratio:.2})"
        );
    }
    assert!(
        annotators::check_password(&hub, "bob", PASSWORD)
            .await
            .expect("check")
            .is_some()
    );
}

#[tokio::test]
async fn an_untrusted_client_cannot_dodge_the_address_limit_with_a_header() {
    // No trusted proxy: X-Forwarded-For is the client's own claim, and ignored.
    let server = spawn_app_with(|_, _| async {}).await;
    annotator(&server, "bob", false).await;
    fail_logins_from(&server, |k| format!("203.0.113.{k}")).await;
    let r = Browser::new(&server)
        .forwarded_for("198.51.100.7")
        .login("bob", PASSWORD)
        .await;
    assert_eq!(r.status(), StatusCode::TOO_MANY_REQUESTS);
    server.stop().await;
}

#[tokio::test]
async fn annotators_cannot_see_each_others_items_or_answers() {
    let (server, records) = spawn_app_with_release().await;
    let a = annotator(&server, "alice", false).await;
    let b = annotator(&server, "bert", false).await;
    let (mine, theirs) = (id(&records, 0), id(&records, 1));
    assign(&server, a, &[&mine]).await;
    assign(&server, b, &[&theirs]).await;
    let (mut alice, alice_csrf) = logged_in(&server, "alice").await;
    let (mut bert, bert_csrf) = logged_in(&server, "bert").await;

    // Bert answers his item.
    assert_eq!(
        bert.get(&format!("/annotate/mini/{theirs}")).await.status(),
        StatusCode::OK
    );
    let r = bert
        .post_json(
            &format!("/annotate/mini/{theirs}/submit"),
            Some(&bert_csrf),
            &json!({"slots": [1, 2], "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(
        r.status(),
        StatusCode::OK,
        "{}",
        r.text().await.unwrap_or_default()
    );

    for path in [
        format!("/annotate/mini/{theirs}"),
        format!("/annotate/mini/{theirs}/answer"),
    ] {
        let r = alice.get(&path).await;
        assert_eq!(r.status(), StatusCode::FORBIDDEN, "{path}");
        assert!(
            r.text()
                .await
                .expect("body")
                .contains("is not assigned to you")
        );
    }
    let r = alice
        .post_json(
            &format!("/annotate/mini/{theirs}/draft"),
            Some(&alice_csrf),
            &json!({"slots": [null, null], "counts": {"placements": 0, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);
    let r = alice
        .post_form(
            &format!("/annotate/mini/{theirs}/skip"),
            &[("csrf", &alice_csrf), ("reason", "x"), ("action", "skip")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);
    // Bert's session token does not work as Alice's CSRF token and vice versa.
    let r = alice
        .post_json(
            &format!("/annotate/mini/{mine}/draft"),
            Some(&bert_csrf),
            &json!({"slots": [null, null], "counts": {"placements": 0, "swaps": 0, "clears": 0, "undos": 0}}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);
    // Annotators do not get the admin pages.
    let (status, html) = alice.text("/admin").await;
    assert_eq!(status, StatusCode::FORBIDDEN);
    assert!(html.contains("the admin pages are for admins"));
    // Unknown items are 404, not 403.
    assert_eq!(
        alice.get("/annotate/mini/nope").await.status(),
        StatusCode::NOT_FOUND
    );
    server.stop().await;
}

#[tokio::test]
async fn no_annotator_response_contains_ground_truth_or_scores() {
    let (server, records) = spawn_app_with_release().await;
    let (mut alice, csrf, ids) = alice_with_every_item(&server, &records).await;
    let forbidden = [
        "gt_answer",
        "ground_truth",
        "key_frame",
        "task_accuracy",
        "pairwise",
        "correct",
    ];
    let check = |what: &str, body: &str| {
        for word in forbidden {
            assert!(!body.contains(word), "{what} contains {word:?}");
        }
    };
    check("queue", &alice.text("/annotate").await.1);
    for (i, item) in ids.iter().enumerate() {
        let (status, html) = alice.text(&format!("/annotate/mini/{item}")).await;
        assert_eq!(status, StatusCode::OK);
        check(item, &html);
        let l = records[i]["images"].as_array().expect("images").len();
        // Submit the ground truth itself: the reply still says nothing about correctness.
        let gt = &records[i]["gt_answer"];
        let r = alice
            .post_json(
                &format!("/annotate/mini/{item}/submit"),
                Some(&csrf),
                &json!({"slots": gt, "counts": {"placements": l - 1, "swaps": 0, "clears": 0, "undos": 0}}),
            )
            .await;
        assert_eq!(r.status(), StatusCode::OK);
        check("submit reply", &r.text().await.expect("body"));
        let (status, answer) = alice.text(&format!("/annotate/mini/{item}/answer")).await;
        assert_eq!(status, StatusCode::OK);
        check("own answer", &answer);
        let answer: Value = serde_json::from_str(&answer).expect("json");
        assert_eq!(&answer["answer"], gt);
        check(
            "item page after",
            &alice.text(&format!("/annotate/mini/{item}")).await.1,
        );
    }
    check("queue after", &alice.text("/annotate").await.1);
    server.stop().await;
}

#[tokio::test]
async fn state_changing_requests_without_the_csrf_token_are_rejected() {
    let (server, records) = spawn_app_with_release().await;
    let a = annotator(&server, "alice", true).await;
    let item = id(&records, 0);
    assign(&server, a, &[&item]).await;
    let (mut alice, csrf) = logged_in(&server, "alice").await;
    let draft = json!({"slots": [2, null], "counts": {"placements": 1, "swaps": 0, "clears": 0, "undos": 0}});
    let path = format!("/annotate/mini/{item}/draft");
    for token in [None, Some("0".repeat(64).as_str()), Some("")] {
        let r = alice.post_json(&path, token, &draft).await;
        assert_eq!(r.status(), StatusCode::FORBIDDEN, "{token:?}");
        assert!(r.text().await.expect("body").contains("CSRF token"));
    }
    let submit = format!("/annotate/mini/{item}/submit");
    let full =
        json!({"slots": [2, 1], "counts": {"placements": 2, "swaps": 0, "clears": 0, "undos": 0}});
    assert_eq!(
        alice.post_json(&submit, None, &full).await.status(),
        StatusCode::FORBIDDEN
    );
    for (path, fields) in [
        (
            format!("/annotate/mini/{item}/skip"),
            vec![("reason", "blurry"), ("action", "flag")],
        ),
        ("/admin/annotators".to_owned(), vec![("name", "mallory")]),
        (
            "/admin/assign".to_owned(),
            vec![("dataset", "mini"), ("mode", "split"), ("annotator", "1")],
        ),
        ("/logout".to_owned(), vec![]),
    ] {
        let r = alice.post_form(&path, &fields).await;
        assert_eq!(r.status(), StatusCode::FORBIDDEN, "{path}");
        let mut wrong = fields.clone();
        wrong.push(("csrf", "f00d"));
        assert_eq!(
            alice.post_form(&path, &wrong).await.status(),
            StatusCode::FORBIDDEN,
            "{path}"
        );
    }
    // Nothing happened: no draft with a placement, no flag, no account, still logged in.
    let placed = count(
        &server.pool,
        "SELECT count(*) FROM drafts WHERE slots != '[]' AND slots != '[null,null]'",
    )
    .await;
    assert_eq!(placed, 0);
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM annotations").await,
        0
    );
    assert_eq!(
        count(&server.pool, "SELECT count(*) FROM annotators").await,
        1
    );
    assert_eq!(alice.get("/annotate").await.status(), StatusCode::OK);
    // The login form has its own double-submit token.
    let mut fresh = Browser::new(&server);
    let r = fresh
        .post_form("/login", &[("name", "alice"), ("password", PASSWORD)])
        .await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);
    // With the token everything works.
    let r = alice.post_json(&path, Some(&csrf), &draft).await;
    assert_eq!(r.status(), StatusCode::OK);
    let r = alice.post_form("/logout", &[("csrf", &csrf)]).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert_eq!(alice.get("/annotate").await.status(), StatusCode::SEE_OTHER);
    server.stop().await;
}

#[tokio::test]
async fn drafts_resume_submissions_are_checked_and_scored_for_the_human_row() {
    let (server, records) = spawn_app_with_release().await;
    let (mut alice, csrf, ids) = alice_with_every_item(&server, &records).await;
    let fwd3 = &ids[0]; // forward, L = 3, ground truth [2, 1]
    let counts = json!({"placements": 3, "swaps": 1, "clears": 1, "undos": 1});

    // The queue sends her to the first item; a saved draft comes back on the page.
    let r = alice.get("/annotate/next").await;
    assert_eq!(
        r.headers()["location"],
        format!("/annotate/mini/{fwd3}").as_str()
    );
    // Read twice, so the server holds her standing on the item in memory before she saves.
    alice.get(&format!("/annotate/mini/{fwd3}")).await;
    let (_, html) = alice.text(&format!("/annotate/mini/{fwd3}")).await;
    assert!(html.contains("&#34;slots&#34;:[null,null]"), "{html}");
    let r = alice
        .post_json(
            &format!("/annotate/mini/{fwd3}/draft"),
            Some(&csrf),
            &json!({"slots": [null, 1], "counts": counts, "history": [[null, null]]}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let (_, html) = alice.text(&format!("/annotate/mini/{fwd3}")).await;
    assert!(html.contains("&#34;slots&#34;:[null,1]"), "{html}");
    let (_, queue) = alice.text("/annotate").await;
    assert!(queue.contains("Resume where you left off"), "{queue}");

    // Bad drafts say what is wrong.
    let r = alice
        .post_json(
            &format!("/annotate/mini/{fwd3}/draft"),
            Some(&csrf),
            &json!({"slots": [1, 1], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let body: Value = r.json().await.expect("json");
    assert_eq!(
        body["error"],
        format!("draft of item '{fwd3}': slots[1]: label 1 is placed twice")
    );
    // The reason is typed: a code of its own, and where (the slot as a person counts it).
    assert_eq!(body["code"], "draft_placed_twice", "{body}");
    assert_eq!(
        body["details"],
        json!({"item": fwd3, "field": "slots", "slot": 2, "label": 1}),
        "{body}"
    );
    let r = alice
        .post_json(
            &format!("/annotate/mini/{fwd3}/submit"),
            Some(&csrf),
            &json!({"slots": [null, 1], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let body: Value = r.json().await.expect("json");
    assert_eq!(
        body["error"],
        format!("item '{fwd3}': slot 1 is empty; fill every slot before submitting")
    );
    // The reason is typed: a stable code and what it names, for a client to act on.
    assert_eq!(body["code"], "slots_empty");
    assert_eq!(
        body["details"],
        json!({"item": fwd3, "slots": "1", "count": 1})
    );

    // Right on the forward item, wrong on the inverse one.
    for (item, slots) in [(fwd3, json!([2, 1])), (&ids[1], json!([1, 2]))] {
        alice.get(&format!("/annotate/mini/{item}")).await;
        let r = alice
            .post_json(
                &format!("/annotate/mini/{item}/submit"),
                Some(&csrf),
                &json!({"slots": slots, "counts": counts}),
            )
            .await;
        assert_eq!(r.status(), StatusCode::OK);
        let (_, html) = alice.text(&format!("/annotate/mini/{item}")).await;
        assert!(html.contains("You have finished this item"), "{html}");
    }
    let r = alice
        .post_json(
            &format!("/annotate/mini/{fwd3}/submit"),
            Some(&csrf),
            &json!({"slots": [1, 2], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::CONFLICT, "an answer is final");
    // Skipping needs a reason; flags reach the admin page.
    let skip = format!("/annotate/mini/{}/skip", ids[2]);
    let r = alice
        .post_form(
            &skip,
            &[("csrf", &csrf), ("reason", " "), ("action", "flag")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("say why in the reason field")
    );
    // An annotator reading the pages in Chinese is told why in Chinese; the API's sentence and
    // code stay as they are.
    alice
        .cookies
        .push(("enact_lang".to_owned(), "zh-CN".to_owned()));
    let r = alice
        .post_form(
            &skip,
            &[("csrf", &csrf), ("reason", ""), ("action", "skip")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    let html = r.text().await.expect("body");
    assert!(html.contains(r#"<html lang="zh-CN""#), "{html}");
    assert!(
        html.contains(&format!("要跳过条目“{}”，请在原因栏中说明原因", ids[2])),
        "{html}"
    );
    assert!(!html.contains("say why"), "{html}");
    let r = alice
        .post_json(
            &format!("/annotate/mini/{fwd3}/submit"),
            Some(&csrf),
            &json!({"slots": [1, 2], "counts": counts}),
        )
        .await;
    assert_eq!(r.status(), StatusCode::CONFLICT);
    let body: Value = r.json().await.expect("json");
    assert_eq!(body["code"], "item_finished");
    assert!(body["error"].as_str().expect("error").is_ascii(), "{body}");
    alice.cookies.retain(|(name, _)| name != "enact_lang");
    let r = alice
        .post_form(
            &skip,
            &[
                ("csrf", &csrf),
                ("reason", "two frames look identical"),
                ("action", "flag"),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);

    let (_, answer) = alice.text(&format!("/annotate/mini/{fwd3}/answer")).await;
    let answer: Value = serde_json::from_str(&answer).expect("json");
    assert_eq!(answer["answer"], json!([2, 1]));
    assert_eq!(
        (
            &answer["placements"],
            &answer["swaps"],
            &answer["clears"],
            &answer["undos"]
        ),
        (&json!(3), &json!(1), &json!(1), &json!(1))
    );
    assert!(
        answer["time_to_first_placement_ms"].as_i64().expect("set")
            <= answer["time_on_item_ms"].as_i64().expect("set")
    );

    let mut conn = server.pool.acquire().await.expect("conn");
    let dataset = store::datasets::by_name(&mut conn, "mini")
        .await
        .expect("q")
        .expect("mini");
    let report =
        enact_hub::app::leaderboard::human_performance(&server.pool.clone().into(), &dataset)
            .await
            .expect("query")
            .expect("two answers");
    let overall = report.overall.as_ref().expect("overall");
    assert_eq!(overall.totals.count, 2, "the flagged item is not an answer");
    assert_eq!(overall.totals.task_accuracy, 0.5);
    assert_eq!(
        report
            .forward_world_modeling
            .as_ref()
            .expect("fwd")
            .totals
            .task_accuracy,
        1.0
    );
    assert_eq!(
        report
            .inverse_world_modeling
            .as_ref()
            .expect("inv")
            .totals
            .task_accuracy,
        0.0
    );
    drop(conn);

    // The admin page shows the flag and the human row.
    annotator(&server, "root", true).await;
    let (mut admin, _) = logged_in(&server, "root").await;
    let (status, html) = admin.text("/admin").await;
    assert_eq!(status, StatusCode::OK);
    assert!(html.contains("two frames look identical"), "{html}");
    assert!(
        html.contains("<th scope=\"row\">overall</th><td>2</td><td>50.0</td>"),
        "{html}"
    );

    // And the leaderboard carries a Human row with the same figures, beside no submission.
    let (status, board) = server.get_json("/api/v1/datasets/mini/leaderboard").await;
    assert_eq!(status, StatusCode::OK);
    let rows = board["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 1, "{board}");
    assert_eq!(rows[0]["source"], "human");
    assert_eq!(rows[0]["model"], "Human");
    assert_eq!(rows[0]["overall"]["task_accuracy"], 0.5);
    assert_eq!(rows[0]["forward"]["total"]["task_accuracy"], 1.0);
    let page = server
        .get("/leaderboard/mini")
        .await
        .text()
        .await
        .expect("page");
    assert!(page.contains("Human"), "{page}");
    // What the row rests on, and its thin cells marked rather than bare.
    let items = rows[0]["human"]["dataset_items"].as_u64().expect("items");
    assert_eq!(rows[0]["human"]["answers"], 2);
    assert_eq!(rows[0]["human"]["items"], 2);
    assert_eq!(rows[0]["human"]["annotators"], 1);
    assert!(
        page.contains(&format!(
            "2 of {items} items, 1 annotator, 2 answers; not ranked"
        )),
        "{page}"
    );
    assert!(page.contains("only 2 answers: fewer than 5"), "{page}");
    assert!(page.contains("only 1 answer: fewer than 5"), "{page}");
    server.stop().await;
}

#[tokio::test]
async fn admins_create_annotators_and_split_datasets_evenly() {
    let (server, records) = spawn_app_with_release().await;
    annotator(&server, "root", true).await;
    let (mut admin, csrf) = logged_in(&server, "root").await;
    let r = admin
        .post_form("/admin/annotators", &[("csrf", &csrf), ("name", "carol")])
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let html = r.text().await.expect("body");
    let start = html.find("<code id=\"invite-url\">").expect("invite shown") + 22;
    let url = &html[start..html[start..].find('<').expect("end") + start];
    assert!(
        url.starts_with(&format!("http://{}/invite/", server.addr)),
        "{url}"
    );
    let r = admin
        .post_form("/admin/annotators", &[("csrf", &csrf), ("name", "carol")])
        .await;
    assert_eq!(r.status(), StatusCode::CONFLICT);
    let r = admin
        .post_form("/admin/annotators", &[("csrf", &csrf), ("name", "<b>")])
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    admin
        .post_form("/admin/annotators", &[("csrf", &csrf), ("name", "dave")])
        .await;
    let mut conn = server.pool.acquire().await.expect("conn");
    let accounts = store::annotations::annotators(&mut conn)
        .await
        .expect("list");
    drop(conn);
    let ids: Vec<String> = accounts
        .iter()
        .filter(|a| a.name == "carol" || a.name == "dave")
        .map(|a| a.id.to_string())
        .collect();
    let r = admin
        .post_form(
            "/admin/assign",
            &[
                ("csrf", &csrf),
                ("dataset", "mini"),
                ("mode", "split"),
                ("annotator", &ids[0]),
                ("annotator", &ids[1]),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("Assigned 4 items of &#39;mini&#39;")
    );
    // Each got one item of each direction (L = 3 and 4 alternate within a direction).
    let mut conn = server.pool.acquire().await.expect("conn");
    for who in &ids {
        let queue = store::annotations::queue(&mut conn, who.parse().expect("id"))
            .await
            .expect("queue");
        assert_eq!(queue.len(), 2);
        let forward = queue
            .iter()
            .filter(|e| e.direction.as_str() == "forward")
            .count();
        assert_eq!(forward, 1, "{who}: {queue:?}");
    }
    drop(conn);
    // Listing unknown ids names them.
    let r = admin
        .post_form(
            "/admin/assign",
            &[
                ("csrf", &csrf),
                ("dataset", "mini"),
                ("mode", "list"),
                ("annotator", &ids[0]),
                ("items", &format!("{} nope", id(&records, 0))),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("not in dataset &#39;mini&#39;: nope")
    );
    server.stop().await;
}

/// Flags write after they read (the draft, for its telemetry). With other writers committing
/// in between, a deferred transaction failed at once with `database is locked` (a 500 for
/// about half the flags under the mixed load); write transactions now take the lock first and
/// queue for it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn flags_queue_behind_concurrent_submissions_instead_of_failing() {
    let server = spawn_app_with(|pool, dir| async move {
        let root = dir.join("release");
        write_balanced_release(&root, &[3, 4], 20);
        import(&pool, &root, &options("mini")).await;
    })
    .await;
    let records: Vec<Value> = {
        let text = std::fs::read_to_string(server.dir().join("release/QA/enact_ordering.jsonl"))
            .expect("release");
        text.lines()
            .map(|l| serde_json::from_str(l).expect("json"))
            .collect()
    };
    let (_, token) = api_token(
        &server.pool,
        "team",
        enact_hub::core::credentials::Role::Admin,
        None,
        None,
    )
    .await;
    let (alice, csrf, ids) = alice_with_every_item(&server, &records).await;
    let server = std::sync::Arc::new(server);
    let writers: Vec<_> = (0..3)
        .map(|w| {
            let (server, token, body) = (server.clone(), token.clone(), answers(&records, &[w]));
            tokio::spawn(async move {
                for k in 0..8 {
                    let reply = submit_to(
                        &server,
                        "mini",
                        &format!("model=w{w}-{k}"),
                        &token,
                        body.clone(),
                    )
                    .await;
                    assert_eq!(reply.status, 201, "{}", reply.text);
                }
            })
        })
        .collect();
    let mut alice = alice;
    for item in ids.iter().take(40) {
        let r = alice
            .post_form(
                &format!("/annotate/mini/{item}/skip"),
                &[("csrf", &csrf), ("reason", "unclear"), ("action", "flag")],
            )
            .await;
        assert_eq!(r.status(), StatusCode::SEE_OTHER, "flag of {item}");
    }
    for writer in writers {
        writer.await.expect("writer");
    }
}
