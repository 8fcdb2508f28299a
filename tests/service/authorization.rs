//! The authorization matrices: every route of the JSON API's route table (the one the router
//! and the OpenAPI document are built from), and every page route found in the source, × every
//! kind of caller (anonymous, malformed, revoked, submitter and admin tokens, another account,
//! an annotator's or an admin's session, forms without or with a wrong CSRF token), with the
//! status each must get. A route the tables below do not know fails the test, so no new route
//! is left out. Callers without the right are refused before the body is read: whatever they
//! send (bodies that are malformed, of the wrong type or too large), they get 401 or 403.

use enact_hub::core::credentials::{Role, Scope};
use enact_hub::web::api_routes;
use enact_hub::web::openapi::{Access, Verb};
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Caller {
    Anonymous,
    Malformed,
    Revoked,
    /// The submitter who owns the submission in the path.
    Owner,
    /// Another submitter: someone else's submission.
    Stranger,
    Admin,
    /// An annotator's browser session, which is no API credential.
    Annotator,
}

const CALLERS: [Caller; 7] = [
    Caller::Anonymous,
    Caller::Malformed,
    Caller::Revoked,
    Caller::Owner,
    Caller::Stranger,
    Caller::Admin,
    Caller::Annotator,
];

/// What a caller must get: success (2xx) or this status.
#[derive(Debug, PartialEq, Eq)]
enum Expected {
    Success,
    Status(u16),
}

fn expected(access: Access, path: &str, caller: Caller) -> Expected {
    let scope = match access {
        Access::Public => return Expected::Success,
        Access::Bearer(scope) => scope,
    };
    match caller {
        Caller::Anonymous | Caller::Malformed | Caller::Revoked | Caller::Annotator => {
            Expected::Status(401)
        }
        Caller::Admin => Expected::Success,
        Caller::Owner | Caller::Stranger if scope == Scope::Admin => Expected::Status(403),
        // Another account's submission is answered like a missing one.
        Caller::Stranger if path.contains("/submissions/{id}") => Expected::Status(404),
        // Only the account that submitted the model (or an admin) sets its metadata.
        Caller::Stranger if path == "/datasets/{dataset}/models/{model}" => Expected::Status(403),
        Caller::Owner | Caller::Stranger => Expected::Success,
    }
}

/// The request body each state-changing route is called with; a route missing here fails.
fn body_of(verb: Verb, path: &str, records: &[Value], n: usize) -> Option<(String, &'static str)> {
    match (verb, path) {
        (Verb::Get, _) => None,
        (Verb::Post, "/datasets/{dataset}/submissions") => {
            Some((answers(records, &[]), "application/x-ndjson"))
        }
        (Verb::Patch, "/admin/submissions/{id}") => {
            Some((json!({"baseline": false}).to_string(), "application/json"))
        }
        (Verb::Put, "/admin/datasets/{dataset}/answers") => {
            Some((json!({"answers": "hidden"}).to_string(), "application/json"))
        }
        (Verb::Post, "/admin/tokens") => Some((
            json!({"name": format!("made-{n}")}).to_string(),
            "application/json",
        )),
        (Verb::Delete, "/admin/tokens/{token_id_or_prefix}") => Some((String::new(), "text/plain")),
        (Verb::Post, "/admin/studies") => Some((
            json!({"name": format!("made-{n}"), "baseline": "mini", "variants": ["Copy/same=mini-copy"]})
                .to_string(),
            "application/json",
        )),
        (Verb::Delete, "/admin/studies/{study}") => Some((String::new(), "text/plain")),
        (Verb::Post, "/admin/imports") => Some((
            json!({"path": "release", "dataset": format!("imported-{n}")}).to_string(),
            "application/json",
        )),
        (Verb::Post, "/admin/jobs/{job}/{change}") => Some((String::new(), "text/plain")),
        (Verb::Post, "/admin/keys/rotate") => Some((String::new(), "text/plain")),
        (Verb::Post, "/admin/rescore") => {
            Some((json!({"dataset": "mini"}).to_string(), "application/json"))
        }
        (Verb::Post, "/admin/runs") => Some((
            json!({"dataset": "mini", "endpoint": "http://127.0.0.1:9/v1", "model": "m",
                   "name": format!("made-{n}")})
            .to_string(),
            "application/json",
        )),
        (Verb::Post, "/admin/runs/{run}/{change}") => Some((String::new(), "text/plain")),
        (Verb::Put, "/admin/datasets/{dataset}/gold") => Some((
            json!({"rate": 5, "share": 0.25, "seed": n}).to_string(),
            "application/json",
        )),
        (Verb::Post, "/datasets/{dataset}/reported") => Some((
            json!({"model": "M", "category": "proprietary", "source": format!("source-{n}"),
                   "task_accuracy": {"forward_3": 50.0}})
            .to_string(),
            "application/json",
        )),
        (Verb::Delete, "/datasets/{dataset}/reported/{reported_id}") => {
            Some((String::new(), "text/plain"))
        }
        (Verb::Put, "/datasets/{dataset}/models/{model}") => Some((
            json!({"category": "open-weight", "family": format!("family-{n}")}).to_string(),
            "application/json",
        )),
        (Verb::Post, "/admin/datasets/{dataset}/challenge/split") => Some((
            json!({"share": 0.5, "seed": n}).to_string(),
            "application/json",
        )),
        (Verb::Patch, "/admin/datasets/{dataset}/challenge") => Some((
            json!({"selection_limit": 2}).to_string(),
            "application/json",
        )),
        (Verb::Put | Verb::Delete, "/submissions/{id}/selection")
        | (Verb::Post, "/admin/datasets/{dataset}/challenge/reveal") => {
            Some((String::new(), "text/plain"))
        }
        (Verb::Delete, "/admin/datasets/{dataset}/gold")
        | (
            Verb::Put | Verb::Delete,
            "/admin/datasets/{dataset}/exclusions/{annotator}",
        )
        | (Verb::Put | Verb::Delete, "/admin/annotators/{annotator}/pause")
        | (Verb::Delete, "/admin/datasets/{dataset}/attention") => {
            Some((String::new(), "text/plain"))
        }
        // To the annotator `Callers::new` makes for it (the session's "ann" is an admin, whom
        // a handover without names leaves out).
        (Verb::Post, "/admin/annotators/{annotator}/handover") => Some((
            json!({"to": ["recipient"]}).to_string(),
            "application/json",
        )),
        (Verb::Put, "/admin/datasets/{dataset}/attention") => Some((
            json!({"rate": 5, "checks": [{"item_id": records[n % 2 + 2]["id"], "instruction": "reverse"}]})
                .to_string(),
            "application/json",
        )),
        (verb, path) => {
            panic!("the authorization matrix has no request for {verb:?} {path}: add it to body_of")
        }
    }
}

/// A new reported row on "mini"; its id.
pub async fn reported_row(server: &TestServer, n: usize) -> i64 {
    let row: enact_hub::core::paper::ReportedModel = serde_json::from_value(json!({
        "model": "Reported", "category": "open-weight", "source": format!("row-{n}"),
        "task_accuracy": {"forward_3": 40.0},
    }))
    .expect("a reported row");
    enact_hub::app::reported::add(
        &enact_hub::app::Hub::from(server.pool.clone()),
        &tester(),
        "mini",
        &row,
    )
    .await
    .expect("added")
    .id
}

fn method(verb: Verb) -> Method {
    verb.method()
}

/// A token or session for each kind of caller, the revoked token revoked.
struct Callers {
    admin: String,
    owner: String,
    stranger: String,
    revoked: String,
    /// The `Cookie` header of an admin annotator's session (no API credential).
    session: String,
}

impl Callers {
    async fn new(server: &TestServer) -> Callers {
        let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
        let (_, owner) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
        let (_, stranger) = api_token(&server.pool, "other", Role::Submitter, None, None).await;
        let (revoked_id, revoked) =
            api_token(&server.pool, "gone", Role::Submitter, None, None).await;
        server
            .call(
                Method::DELETE,
                &format!("/api/v1/admin/tokens/{revoked_id}"),
            )
            .bearer(&admin)
            .expect(204)
            .await;
        crate::annotate::annotator(server, "ann", true).await;
        crate::annotate::annotator(server, "recipient", false).await;
        let (browser, _) = crate::annotate::logged_in_on(server, "ann", "/annotate").await;
        Callers {
            admin,
            owner,
            stranger,
            revoked,
            session: browser.cookie_header(),
        }
    }

    /// `call` with `caller`'s credential.
    fn credential(&self, call: Call, caller: Caller) -> Call {
        match caller {
            Caller::Anonymous => call,
            Caller::Malformed => call.header("Authorization", "Bearer not-a-token"),
            Caller::Revoked => call.bearer(&self.revoked),
            Caller::Owner => call.bearer(&self.owner),
            Caller::Stranger => call.bearer(&self.stranger),
            Caller::Admin => call.bearer(&self.admin),
            Caller::Annotator => call.header("Cookie", &self.session),
        }
    }
}

#[tokio::test]
async fn every_api_route_answers_every_caller_as_the_matrix_says() {
    let (server, records) = spawn_app_with_release().await;
    let callers = Callers::new(&server).await;
    let submission = {
        let reply = submit_to(
            &server,
            "mini",
            "model=m",
            &callers.owner,
            answers(&records, &[]),
        )
        .await;
        assert_eq!(reply.status, 201, "{}", reply.text);
        reply.id()
    };
    // A second row, for the comparison of two.
    let second = {
        let reply = submit_to(
            &server,
            "mini",
            "model=m2",
            &callers.owner,
            answers(&records, &[1]),
        )
        .await;
        assert_eq!(reply.status, 201, "{}", reply.text);
        reply.id()
    };
    mini_study(&server, "matrix").await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    let (_, item_json) = server
        .get_json(&format!("/api/v1/datasets/mini/items/{item}"))
        .await;
    let frame_url = item_json.to_string();
    let sha = frame_url
        .split("/api/v1/frames/")
        .nth(1)
        .map(|rest| rest[..64].to_owned())
        .expect("a frame url in the item");

    let mut cells = 0;
    let mut n = 0;
    for route in api_routes() {
        for caller in CALLERS {
            n += 1;
            let mut path = route.path.to_owned();
            for param in route.path_params() {
                let value = match param {
                    "dataset" => "mini".to_owned(),
                    "item_id" => item.clone(),
                    "sha256" => sha.clone(),
                    "id" => submission.to_string(),
                    // A fresh token for every revocation.
                    "token_id_or_prefix" => {
                        api_token(&server.pool, &format!("t{n}"), Role::Submitter, None, None)
                            .await
                            .0
                            .to_string()
                    }
                    // A fresh study for every deletion.
                    "study" if route.verb == Verb::Delete => {
                        mini_study(&server, &format!("doomed-{n}")).await;
                        format!("doomed-{n}")
                    }
                    "study" => "matrix".to_owned(),
                    // A fresh queued run for every call, so that cancelling it succeeds; a
                    // run's public route needs its dataset's answers public (another route
                    // of the matrix hides them).
                    "run" => {
                        if route.path.starts_with("/runs/") {
                            set_mini_answers(
                                &server.pool,
                                enact_hub::core::dataset::AnswerVisibility::Public,
                            )
                            .await;
                        }
                        let run = matrix_run(&server, n).await;
                        // A run's stamp is shown once it has submitted: filed as the
                        // owner's published submission.
                        if route.path.ends_with("/stamp") {
                            let mut tx = write_tx(&server.pool).await;
                            enact_hub::store::runs::set_submission(
                                &mut tx,
                                run,
                                submission,
                                r#"{"model": "m", "endpoint_host": "127.0.0.1:9"}"#,
                            )
                            .await
                            .expect("the run linked to a submission");
                            tx.commit().await.expect("commit");
                        }
                        run.to_string()
                    }
                    // A fresh queued job for every call, so that cancelling it succeeds.
                    "job" => enact_hub::app::rescore::request(
                        &enact_hub::app::Hub::from(server.pool.clone()),
                        &tester(),
                        Some("mini"),
                    )
                    .await
                    .expect("a queued rescore")
                    .0
                    .to_string(),
                    "change" => "cancel".to_owned(),
                    // The owner's model.
                    "model" => "m".to_owned(),
                    // A fresh reported row for every call, so that removing it succeeds.
                    "reported_id" => reported_row(&server, n).await.to_string(),
                    // The annotator behind the callers' session.
                    "annotator" => "ann".to_owned(),
                    other => panic!(
                        "the authorization matrix cannot fill {{{other}}} in {}",
                        route.path
                    ),
                };
                path = path.replace(&format!("{{{param}}}"), &value);
            }
            // The required query parameters among the routes: a submission's model, a report's,
            // the quality figures' dataset, the two rows of a comparison.
            if route.path == "/admin/annotators/quality" {
                path.push_str("?dataset=mini");
            }
            if route.path == "/datasets/{dataset}/submissions" {
                path.push_str("?model=matrix");
            }
            if route.path == "/studies/{study}/report" {
                path.push_str("?model=m");
            }
            // An item's answers are public only while its dataset's are (another route of the
            // matrix hides them).
            if route.path == "/datasets/{dataset}/items/{item_id}/answers" {
                set_mini_answers(
                    &server.pool,
                    enact_hub::core::dataset::AnswerVisibility::Public,
                )
                .await;
            }
            // Only a dataset whose answers are hidden can be split (other routes of the matrix
            // make them public); the challenge's other routes come after the split.
            if route.path == "/admin/datasets/{dataset}/challenge/split" {
                set_mini_answers(
                    &server.pool,
                    enact_hub::core::dataset::AnswerVisibility::Hidden,
                )
                .await;
            }
            if route.path == "/datasets/{dataset}/compare" {
                path.push_str(&format!("?a={submission}&b={second}"));
            }
            // So is the explorer (to anyone but an admin's browser session).
            if route.path == "/datasets/{dataset}/explore" {
                set_mini_answers(
                    &server.pool,
                    enact_hub::core::dataset::AnswerVisibility::Public,
                )
                .await;
            }
            let mut call = callers.credential(
                server.call(method(route.verb), &format!("/api/v1{path}")),
                caller,
            );
            if let Some((body, content_type)) = body_of(route.verb, route.path, &records, n) {
                call = call.header("Content-Type", content_type).body(body);
            }
            let reply = call.send().await;
            let status = reply.status.as_u16();
            let want = expected(route.access, route.path, caller);
            let ok = match want {
                Expected::Success => (200..300).contains(&status),
                Expected::Status(s) => status == s,
            };
            assert!(
                ok,
                "{:?} {} as {caller:?}: got {}, expected {want:?}: {}",
                route.verb, route.path, status, reply.text
            );
            if status >= 400 {
                // Every refusal is the API's JSON error body.
                assert!(reply.json()["error"].is_string(), "{}", reply.text);
            }
            cells += 1;
        }
    }
    let routes = api_routes().len();
    assert_eq!(cells, routes * CALLERS.len());
    assert!(routes >= 15, "{routes} routes");
    server.stop().await;
}

/// Bodies a handler would refuse (400, 413, 415 or 422) if it read them: a caller without the
/// right must hear 401 or 403 instead, whatever it sends. (Content type, body, what it is.)
fn malformed_bodies() -> Vec<(&'static str, String, &'static str)> {
    vec![
        (
            "application/json",
            "{\"name\": ".to_owned(),
            "truncated JSON",
        ),
        (
            "application/json",
            json!({"unknown": true, "name": 7, "answers": "both"}).to_string(),
            "JSON of the wrong shape",
        ),
        ("application/xml", "<name>x</name>".to_owned(), "not JSON"),
        ("text/plain", String::new(), "an empty body"),
        (
            "application/x-www-form-urlencoded",
            "csrf=%ZZ&dataset=%&mode".to_owned(),
            "a broken form",
        ),
        (
            "application/json",
            format!("[\"{}\"]", "x".repeat(3 * 1024 * 1024)),
            "a body over the limit",
        ),
    ]
}

#[tokio::test]
async fn callers_without_the_right_are_refused_before_any_body_is_read() {
    let server = spawn_app_with(|_, _| async {}).await;
    let callers = Callers::new(&server).await;

    let mut cells = 0;
    for route in api_routes() {
        let Access::Bearer(scope) = route.access else {
            continue;
        };
        // Nothing in the path names anything stored, and no query parameter is given (the
        // submission route requires `model`): a handler reached would refuse.
        let mut path = route.path.to_owned();
        for param in route.path_params() {
            path = path.replace(&format!("{{{param}}}"), "%ZZnot-stored");
        }
        let mut refused = vec![
            Caller::Anonymous,
            Caller::Malformed,
            Caller::Revoked,
            Caller::Annotator,
        ];
        if scope == Scope::Admin {
            refused.push(Caller::Owner);
        }
        for caller in refused {
            let Expected::Status(want) = expected(route.access, route.path, caller) else {
                panic!("{caller:?} may call {:?} {}", route.verb, route.path);
            };
            for (content_type, body, what) in malformed_bodies() {
                let call = server
                    .call(route.verb.method(), &format!("/api/v1{path}"))
                    .header("Content-Type", content_type)
                    .header("Idempotency-Key", "");
                let reply = callers.credential(call, caller).body(body).send().await;
                assert_eq!(
                    reply.status.as_u16(),
                    want,
                    "{:?} {} as {caller:?} with {what}: {}",
                    route.verb,
                    route.path,
                    reply.text
                );
                assert!(reply.json()["error"].is_string(), "{}", reply.text);
                cells += 1;
            }
        }
    }
    assert!(cells >= 10 * 4 * malformed_bodies().len(), "{cells} cells");
    server.stop().await;
}

/// Who a page route is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Page {
    /// Anyone.
    Public,
    /// A form anyone may post without a session or CSRF token (the language switch): a bad
    /// form is 400, never 401 or 403.
    PublicForm,
    /// Anyone, with a secret in the path (a bogus one is 404 for everyone).
    Link,
    /// A public form guarded by its own CSRF cookie (login, invite): refused without it (or,
    /// for a bogus invite, as unknown).
    Form,
    /// A logged-in annotator.
    Session,
    /// A logged-in admin.
    Admin,
    /// A metrics scraper: an admin API token (or the server's metrics token), not a session.
    Scraper,
}

/// Every page route: (method, path, who it is for). The source is scanned for `.route("…")`
/// below, so a page route missing here fails the test.
const PAGES: &[(&str, &str, Page)] = &[
    ("GET", "/", Page::Public),
    ("GET", "/healthz", Page::Public),
    ("GET", "/metrics", Page::Scraper),
    ("GET", "/datasets/{dataset}", Page::Public),
    ("GET", "/datasets/{dataset}/items/{item_id}", Page::Public),
    ("GET", "/datasets/{dataset}/paper", Page::Public),
    ("GET", "/datasets/{dataset}/compare", Page::Public),
    // Public for a dataset with public answers (the matrix makes `mini`'s public).
    ("GET", "/datasets/{dataset}/explore", Page::Public),
    ("GET", "/datasets/{dataset}/paper.tar", Page::Public),
    (
        "GET",
        "/datasets/{dataset}/paper/files/{file}",
        Page::Public,
    ),
    ("GET", "/leaderboard/{dataset}", Page::Public),
    ("GET", "/leaderboard/{dataset}/errors", Page::Public),
    ("GET", "/leaderboard/{dataset}/errors/{entry}", Page::Public),
    ("GET", "/api/docs", Page::Public),
    ("GET", "/static/app.css", Page::Public),
    ("GET", "/static/annotate.js", Page::Public),
    ("GET", "/static/favicon.svg", Page::Public),
    ("GET", "/favicon.ico", Page::Public),
    ("GET", "/login", Page::Public),
    ("POST", "/login", Page::Form),
    ("POST", "/locale", Page::PublicForm),
    ("GET", "/invite/{token}", Page::Link),
    ("POST", "/invite/{token}", Page::Form),
    ("GET", "/login/link/{token}", Page::Link),
    ("POST", "/logout", Page::Session),
    ("GET", "/annotate", Page::Session),
    ("GET", "/annotate/next", Page::Session),
    ("GET", "/annotate/{dataset}/{item_id}", Page::Session),
    ("POST", "/annotate/{dataset}/{item_id}/draft", Page::Session),
    (
        "POST",
        "/annotate/{dataset}/{item_id}/submit",
        Page::Session,
    ),
    ("POST", "/annotate/{dataset}/{item_id}/skip", Page::Session),
    ("GET", "/annotate/{dataset}/{item_id}/answer", Page::Session),
    ("GET", "/admin", Page::Admin),
    ("POST", "/admin/annotators", Page::Admin),
    ("POST", "/admin/assign", Page::Admin),
    ("GET", "/admin/tokens", Page::Admin),
    ("POST", "/admin/tokens", Page::Admin),
    ("POST", "/admin/tokens/revoke", Page::Admin),
    ("GET", "/admin/audit", Page::Admin),
    ("POST", "/admin/rescore", Page::Admin),
    ("POST", "/admin/imports", Page::Admin),
    (
        "POST",
        "/admin/datasets/{dataset}/agreement-protocol",
        Page::Admin,
    ),
    ("GET", "/admin/datasets/{dataset}/report", Page::Admin),
    ("GET", "/admin/datasets/{dataset}/report.json", Page::Admin),
    ("GET", "/admin/datasets/{dataset}/report.tar", Page::Admin),
    ("GET", "/admin/datasets/{dataset}/reported", Page::Admin),
    ("GET", "/admin/datasets/{dataset}/flags", Page::Admin),
    (
        "POST",
        "/admin/datasets/{dataset}/reported/paper",
        Page::Admin,
    ),
    (
        "POST",
        "/admin/datasets/{dataset}/reported/tables",
        Page::Admin,
    ),
    (
        "POST",
        "/admin/datasets/{dataset}/reported/remove",
        Page::Admin,
    ),
    ("POST", "/admin/datasets/{dataset}/models", Page::Admin),
    ("GET", "/studies", Page::Public),
    ("GET", "/studies/{study}", Page::Public),
    ("GET", "/admin/studies", Page::Admin),
    ("POST", "/admin/studies", Page::Admin),
    ("POST", "/admin/studies/delete", Page::Admin),
    ("GET", "/admin/quality", Page::Admin),
    ("POST", "/admin/quality/gold", Page::Admin),
    ("POST", "/admin/quality/gold/clear", Page::Admin),
    ("POST", "/admin/quality/exclusion", Page::Admin),
    ("POST", "/admin/quality/pause", Page::Admin),
    ("POST", "/admin/quality/handover", Page::Admin),
    ("POST", "/admin/quality/attention", Page::Admin),
    ("POST", "/admin/quality/attention/clear", Page::Admin),
    ("GET", "/admin/challenges", Page::Admin),
    ("POST", "/admin/challenges/split", Page::Admin),
    ("POST", "/admin/challenges/settings", Page::Admin),
    ("POST", "/admin/challenges/reveal", Page::Admin),
    ("GET", "/admin/runs", Page::Admin),
    ("POST", "/admin/runs", Page::Admin),
    ("GET", "/admin/runs/{run}", Page::Admin),
    ("GET", "/admin/runs/{run}/progress", Page::Admin),
    ("POST", "/admin/runs/{run}/control", Page::Admin),
    ("GET", "/admin/runs/{run}/responses.jsonl", Page::Admin),
    // Public for a dataset with public answers (the matrix makes `mini`'s public).
    ("GET", "/runs/{run}", Page::Public),
    ("GET", "/runs/{run}/responses.jsonl", Page::Public),
    ("GET", "/static/run_progress.js", Page::Public),
    ("GET", "/static/episode.js", Page::Public),
    ("GET", "/static/episode.css", Page::Public),
    ("GET", "/episodes", Page::Session),
    ("GET", "/episodes/{name}", Page::Session),
    ("POST", "/episodes/{name}/describe", Page::Session),
    ("POST", "/episodes/{name}/draft", Page::Session),
    ("POST", "/episodes/{name}/graphs", Page::Session),
    ("GET", "/admin/episodes/new", Page::Admin),
    ("POST", "/admin/episodes", Page::Admin),
    ("POST", "/admin/episodes/folder", Page::Admin),
    ("GET", "/admin/episodes/{name}/compare", Page::Admin),
    ("POST", "/admin/episodes/{name}/resolve", Page::Admin),
    ("GET", "/admin/episodes/{name}/export", Page::Admin),
];

/// The literal paths of every `.route(` in the web adapter's source.
fn routes_in_source() -> std::collections::BTreeSet<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/enact-web/src");
    let mut found = std::collections::BTreeSet::new();
    for entry in std::fs::read_dir(dir).expect("crates/enact-web/src") {
        let text = std::fs::read_to_string(entry.expect("entry").path()).expect("source");
        for (i, _) in text.match_indices(".route(") {
            let rest = text[i + 7..].trim_start();
            if let Some(literal) = rest.strip_prefix('"') {
                found.insert(literal[..literal.find('"').expect("closing quote")].to_owned());
            }
        }
    }
    found
}

#[tokio::test]
async fn every_page_route_answers_every_caller_as_the_matrix_says() {
    use crate::annotate::{annotator, assign, logged_in_on};

    let listed: std::collections::BTreeSet<String> =
        PAGES.iter().map(|(_, p, _)| (*p).to_owned()).collect();
    for path in routes_in_source() {
        assert!(
            listed.contains(&path),
            "page route {path} is not in the authorization matrix (PAGES)"
        );
    }

    let (server, records) = spawn_app_with_release().await;
    let ann = annotator(&server, "ann", false).await;
    let root = annotator(&server, "root", true).await;
    let item = records[0]["id"].as_str().expect("id").to_owned();
    assign(&server, ann, &[&item]).await;
    assign(&server, root, &[&item]).await;
    let (_, submitter) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, admin_token) = api_token(&server.pool, "boss", Role::Admin, None, None).await;
    mini_study(&server, "pages").await;
    let submission = submit_to(
        &server,
        "mini",
        "model=m",
        &submitter,
        answers(&records, &[]),
    )
    .await
    .id();
    set_mini_answers(
        &server.pool,
        enact_hub::core::dataset::AnswerVisibility::Public,
    )
    .await;
    let run = matrix_run(&server, 0).await;

    let mut cells = 0;
    for &(verb, pattern, page) in PAGES {
        let path = pattern
            .replace("{run}", &run.to_string())
            .replace("{dataset}", "mini")
            .replace("{item_id}", &item)
            .replace("{entry}", &submission.to_string())
            .replace("{token}", "not-a-real-secret")
            .replace("{study}", "pages")
            .replace("{file}", "task_accuracy.csv");
        let post = verb == "POST";
        // Anonymous, API tokens (which pages do not take), annotator and admin (both with the
        // page's CSRF token), and for forms an admin without it or with another one. Sessions
        // are fresh per cell: logging out must not spoil the next one.
        let callers: &[&str] = if post {
            &[
                "anonymous",
                "submitter token",
                "admin token",
                "annotator",
                "admin",
                "admin without CSRF",
                "admin with a wrong CSRF",
            ]
        } else {
            &[
                "anonymous",
                "submitter token",
                "admin token",
                "annotator",
                "admin",
            ]
        };
        for &caller in callers {
            let (mut browser, csrf) = match caller {
                "anonymous" => (crate::annotate::Browser::new(&server), String::new()),
                "submitter token" => (
                    crate::annotate::Browser::new(&server).with_bearer(&submitter),
                    String::new(),
                ),
                "admin token" => (
                    crate::annotate::Browser::new(&server).with_bearer(&admin_token),
                    String::new(),
                ),
                "annotator" => logged_in_on(&server, "ann", "/annotate").await,
                _ => logged_in_on(&server, "root", "/admin").await,
            };
            let response = if post {
                let wrong = "0".repeat(64);
                let fields: Vec<(&str, &str)> = match caller {
                    "admin without CSRF" => Vec::new(),
                    "admin with a wrong CSRF" => vec![("csrf", wrong.as_str())],
                    _ => vec![("csrf", csrf.as_str())],
                };
                browser.post_form(&path, &fields).await
            } else {
                browser.get(&path).await
            };
            let status = response.status().as_u16();
            let to_login = response
                .headers()
                .get("location")
                .is_some_and(|l| l.to_str().unwrap_or("").starts_with("/login"));
            let what = format!("{verb} {pattern} as {caller}: {status}");
            assert!(status < 500, "{what}");
            match (page, caller) {
                (Page::Public, _) => assert!(status < 400, "{what}"),
                (Page::Scraper, "admin token") => assert_eq!(status, 200, "{what}"),
                (Page::Scraper, "submitter token") => assert_eq!(status, 403, "{what}"),
                (Page::Scraper, _) => assert_eq!(status, 401, "{what}"),
                (Page::PublicForm, _) => assert!(status != 401 && status != 403, "{what}"),
                (Page::Link, _) => assert_eq!(status, 404, "{what}"),
                // Refused: the form's own CSRF is missing (403), or the invite is unknown (404).
                (Page::Form, _) => assert!(status == 403 || status == 404, "{what}"),
                // An API token is not a session: as anonymous.
                (Page::Session | Page::Admin, "anonymous" | "submitter token" | "admin token") => {
                    assert!(status == 401 || (status == 303 && to_login), "{what}")
                }
                (_, "admin without CSRF" | "admin with a wrong CSRF") => {
                    assert_eq!(status, 403, "{what}")
                }
                (Page::Admin, "annotator") => assert_eq!(status, 403, "{what}"),
                // Allowed: anything but a refusal of who they are (a bad form is 400).
                // (Logging out succeeds by going to the login page.)
                (Page::Session | Page::Admin, _) => assert!(
                    status != 401 && status != 403 && (!to_login || pattern == "/logout"),
                    "{what}"
                ),
            }
            cells += 1;
        }
    }
    let forms = PAGES.iter().filter(|(verb, _, _)| *verb == "POST").count();
    assert_eq!(cells, PAGES.len() * 5 + forms * 2);
    server.stop().await;
}

#[tokio::test]
async fn page_callers_without_the_right_are_refused_before_any_form_is_read() {
    use crate::annotate::{annotator, logged_in_on};

    let (server, _) = spawn_app_with_release().await;
    annotator(&server, "ann", false).await;
    let (browser, _) = logged_in_on(&server, "ann", "/annotate").await;
    let session = browser.cookie_header();

    let mut cells = 0;
    for &(verb, pattern, page) in PAGES {
        // Who must be refused, and with what: no session is 401 (a page GET goes to the login
        // form instead), an annotator on an admin page 403.
        let refused: &[(&str, u16)] = match page {
            Page::Session => &[("anonymous", 401)],
            Page::Admin => &[("anonymous", 401), ("annotator", 403)],
            Page::Scraper => &[("anonymous", 401), ("annotator", 401)],
            Page::Public | Page::PublicForm | Page::Link | Page::Form => continue,
        };
        let path = pattern
            .replace("{dataset}", "%ZZnot-stored")
            .replace("{item_id}", "%ZZnot-stored")
            .replace("{study}", "%ZZnot-stored")
            .replace("{run}", "%ZZnot-stored");
        for &(caller, want) in refused {
            for (content_type, body, what) in malformed_bodies() {
                let method = if verb == "POST" {
                    Method::POST
                } else {
                    Method::GET
                };
                let mut call = server
                    .call(method, &format!("{path}?step_length=banana&%ZZ"))
                    .header("Content-Type", content_type)
                    // Asked for JSON, a GET without a session is 401 rather than a redirect.
                    .header("Accept", "application/json");
                if caller == "annotator" {
                    call = call.header("Cookie", &session);
                }
                let reply = call.body(body).send().await;
                assert_eq!(
                    reply.status.as_u16(),
                    want,
                    "{verb} {pattern} as {caller} with {what}: {}",
                    reply.text
                );
                cells += 1;
            }
        }
    }
    assert!(cells >= 20 * malformed_bodies().len(), "{cells} cells");
    server.stop().await;
}

/// Every `.rs` file under `dir`, with its text.
fn sources_under(dir: &std::path::Path, out: &mut Vec<(std::path::PathBuf, String)>) {
    for entry in std::fs::read_dir(dir).expect("source folder") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            sources_under(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&path).expect("source");
            out.push((path, text));
        }
    }
}

/// The route table decides who may call a route, in one place: no handler or use case checks
/// a token's scope or a session's role by hand (where it would run after the body is read).
#[test]
fn scopes_and_roles_are_checked_only_where_the_route_tables_say() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = Vec::new();
    for dir in [
        "src",
        "crates/enact-web/src",
        "crates/enact-app/src",
        "crates/enact-store/src",
    ] {
        sources_under(&root.join(dir), &mut sources);
    }
    let mut by_hand = Vec::new();
    for (path, text) in &sources {
        let file = path
            .strip_prefix(root)
            .expect("under the crate")
            .to_string_lossy();
        for (n, line) in text.lines().enumerate() {
            let checks_scope = line.contains(".require(Scope::");
            let checks_role = line.contains("require_admin(");
            // `tokens::authorize` is the one scope check, run by the table's layer.
            if (checks_scope && file != "crates/enact-app/src/tokens.rs") || checks_role {
                by_hand.push(format!("{file}:{}: {}", n + 1, line.trim()));
            }
        }
    }
    assert!(
        by_hand.is_empty(),
        "authorization checked by hand:\n{}",
        by_hand.join("\n")
    );
    assert!(sources.len() > 50, "{} source files", sources.len());
}

/// A model run queued on the server (never worked: its endpoint is closed), by id.
async fn matrix_run(server: &TestServer, n: usize) -> i64 {
    let hub = enact_hub::app::Hub::from(server.pool.clone());
    let spec = enact_hub::app::runs::RunSpec {
        dataset: "mini".to_owned(),
        endpoint: "http://127.0.0.1:9/v1".to_owned(),
        model: "m".to_owned(),
        name: Some(format!("matrix-run-{n}")),
        params: Default::default(),
        limit: None,
        retry_failed: false,
        submit_as: None,
        prices: Default::default(),
    };
    let (run, _) = enact_hub::app::runs::start(&hub, &tester(), &spec, &Default::default())
        .await
        .expect("a run started");
    run.id
}
