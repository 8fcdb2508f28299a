//! Hostile and malformed input, one table: each case is a request a careless or hostile client
//! might send, with the status it must get. Every refusal is the API's JSON `{"error": …}` body,
//! and nothing here may crash the server or reach a 5xx. A field value the API refuses is 400
//! (a malformed request, as the OpenAPI document says); a submission body it cannot read is 422
//! with the line.

use enact_hub::core::credentials::Role;
use reqwest::Method;

use crate::helpers::*;

/// Who sends a case.
#[derive(Clone, Copy)]
enum As {
    Nobody,
    Submitter,
    Admin,
}

struct Case {
    what: &'static str,
    method: Method,
    path: String,
    who: As,
    content_type: Option<&'static str>,
    body: Vec<u8>,
    status: u16,
}

fn case(what: &'static str, method: Method, path: impl Into<String>, status: u16) -> Case {
    Case {
        what,
        method,
        path: path.into(),
        who: As::Nobody,
        content_type: None,
        body: Vec::new(),
        status,
    }
}

impl Case {
    fn by(mut self, who: As) -> Case {
        self.who = who;
        self
    }

    fn with(mut self, content_type: &'static str, body: impl Into<Vec<u8>>) -> Case {
        self.content_type = Some(content_type);
        self.body = body.into();
        self
    }
}

#[tokio::test]
async fn hostile_requests_get_clear_refusals() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, team) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let reply = submit_to(&server, "mini", "model=m", &team, answers(&records, &[])).await;
    assert_eq!(reply.status, 201, "{}", reply.text);
    let id = reply.id();
    let item = records[0]["id"].as_str().expect("id").to_owned();
    let submit = "/api/v1/datasets/mini/submissions?model=m";
    let line = |answer: &str| format!("{{\"id\": \"{item}\", \"answer\": {answer}}}\n");
    let nested = "[".repeat(5000) + &"]".repeat(5000);
    let json = "application/json";
    let ndjson = "application/x-ndjson";
    use Method as M;
    let cases = vec![
        // Reading: paths and queries.
        case("unknown dataset", M::GET, "/api/v1/datasets/nope", 404),
        case(
            "markup as a dataset name",
            M::GET,
            "/api/v1/datasets/%3Cscript%3E",
            404,
        ),
        case(
            "dot-dot in a path",
            M::GET,
            "/api/v1/datasets/..%2F..%2Fetc%2Fpasswd",
            404,
        ),
        case(
            "NUL in an item id",
            M::GET,
            "/api/v1/datasets/mini/items/%00",
            404,
        ),
        case(
            "a 10 kB item id",
            M::GET,
            format!("/api/v1/datasets/mini/items/{}", "a".repeat(10_000)),
            404,
        ),
        case(
            "per_page not a number",
            M::GET,
            "/api/v1/datasets/mini/items?per_page=ten",
            400,
        ),
        case(
            "per_page zero",
            M::GET,
            "/api/v1/datasets/mini/items?per_page=0",
            400,
        ),
        case(
            "per_page huge",
            M::GET,
            "/api/v1/datasets/mini/items?per_page=99999999999999999999",
            400,
        ),
        case(
            "unknown direction",
            M::GET,
            "/api/v1/datasets/mini/items?direction=sideways",
            400,
        ),
        case(
            "step length out of range",
            M::GET,
            "/api/v1/datasets/mini/items?step_length=99",
            400,
        ),
        case(
            "frame hash not hex",
            M::GET,
            "/api/v1/frames/not-a-hash",
            404,
        ),
        case(
            "frame hash unknown",
            M::GET,
            format!("/api/v1/frames/{}", "0".repeat(64)),
            404,
        ),
        case(
            "frame hash too long",
            M::GET,
            format!("/api/v1/frames/{}", "a".repeat(65)),
            404,
        ),
        case(
            "leaderboard sort unknown",
            M::GET,
            "/api/v1/datasets/mini/leaderboard?sort=best",
            400,
        ),
        case(
            "leaderboard page zero",
            M::GET,
            "/api/v1/datasets/mini/leaderboard?page=0",
            400,
        ),
        case(
            "leaderboard per_page too large",
            M::GET,
            "/api/v1/datasets/mini/leaderboard?per_page=1001",
            400,
        ),
        case(
            "leaderboard chart ids not numbers",
            M::GET,
            "/api/v1/datasets/mini/leaderboard?chart=a,b",
            400,
        ),
        case(
            "errors top zero",
            M::GET,
            "/api/v1/datasets/mini/errors?top=0",
            400,
        ),
        case(
            "errors pick not ids",
            M::GET,
            "/api/v1/datasets/mini/errors?pick=1,x",
            400,
        ),
        case(
            "errors unknown parameter",
            M::GET,
            "/api/v1/datasets/mini/errors?evil=1",
            400,
        ),
        case(
            "submission id not a number",
            M::GET,
            "/api/v1/submissions/abc",
            404,
        )
        .by(As::Submitter),
        case(
            "submission id beyond i64",
            M::GET,
            "/api/v1/submissions/99999999999999999999",
            404,
        )
        .by(As::Submitter),
        case(
            "negative submission id",
            M::GET,
            "/api/v1/submissions/-1",
            404,
        )
        .by(As::Submitter),
        case("no such route", M::GET, "/api/v1/no-such-route", 404),
        // Submitting.
        case("empty submission", M::POST, submit, 422).by(As::Submitter),
        case("invalid UTF-8", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, vec![0xff, 0xfe, b'{', b'}']),
        case("not JSON", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, "this is not json\n"),
        case("an answer that is an object", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, line("{\"a\": 1}")),
        case("deeply nested JSON", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, nested.clone()),
        case("unknown item id", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, "{\"id\": \"nope\", \"answer\": \"[1, 2]\"}\n"),
        case("an id that is a number", M::POST, submit, 422)
            .by(As::Submitter)
            .with(ndjson, "{\"id\": 7, \"answer\": \"[1]\"}\n"),
        case(
            "no model",
            M::POST,
            "/api/v1/datasets/mini/submissions",
            400,
        )
        .by(As::Submitter)
        .with(ndjson, line("\"[1, 2]\"")),
        case(
            "a 201-character model",
            M::POST,
            format!(
                "/api/v1/datasets/mini/submissions?model={}",
                "m".repeat(201)
            ),
            400,
        )
        .by(As::Submitter)
        .with(ndjson, line("\"[1, 2]\"")),
        case("a 300-character Idempotency-Key", M::POST, submit, 400)
            .by(As::Submitter)
            .with(ndjson, line("\"[1, 2]\"")),
        case(
            "submitting to no dataset",
            M::POST,
            "/api/v1/datasets/nope/submissions?model=m",
            404,
        )
        .by(As::Submitter)
        .with(ndjson, line("\"[1, 2]\"")),
        // Admin writes.
        case(
            "listing change not JSON",
            M::PATCH,
            format!("/api/v1/admin/submissions/{id}"),
            400,
        )
        .by(As::Admin)
        .with(json, "{baseline: yes"),
        case(
            "listing change with a wrong content type",
            M::PATCH,
            format!("/api/v1/admin/submissions/{id}"),
            415,
        )
        .by(As::Admin)
        .with("text/plain", "{}"),
        case(
            "listing change with an unknown field",
            M::PATCH,
            format!("/api/v1/admin/submissions/{id}"),
            422,
        )
        .by(As::Admin)
        .with(json, "{\"delete\": true}"),
        case(
            "listing visibility unknown",
            M::PATCH,
            format!("/api/v1/admin/submissions/{id}"),
            400,
        )
        .by(As::Admin)
        .with(json, "{\"visibility\": \"everyone\"}"),
        case(
            "answers visibility unknown",
            M::PUT,
            "/api/v1/admin/datasets/mini/answers",
            422,
        )
        .by(As::Admin)
        .with(json, "{\"answers\": \"maybe\"}"),
        case(
            "token for an empty name",
            M::POST,
            "/api/v1/admin/tokens",
            400,
        )
        .by(As::Admin)
        .with(json, "{\"name\": \"\"}"),
        case(
            "token for a 101-character name",
            M::POST,
            "/api/v1/admin/tokens",
            400,
        )
        .by(As::Admin)
        .with(json, format!("{{\"name\": \"{}\"}}", "n".repeat(101))),
        case(
            "token with an unknown role",
            M::POST,
            "/api/v1/admin/tokens",
            400,
        )
        .by(As::Admin)
        .with(json, "{\"name\": \"x\", \"role\": \"root\"}"),
        case(
            "token with a negative quota",
            M::POST,
            "/api/v1/admin/tokens",
            400,
        )
        .by(As::Admin)
        .with(json, "{\"name\": \"x\", \"daily_quota\": -5}"),
        case(
            "token with a huge quota",
            M::POST,
            "/api/v1/admin/tokens",
            400,
        )
        .by(As::Admin)
        .with(json, "{\"name\": \"x\", \"daily_quota\": 1e400}"),
        case(
            "revoking no token",
            M::DELETE,
            "/api/v1/admin/tokens/abc",
            404,
        )
        .by(As::Admin),
        case(
            "a body over the limit",
            M::PATCH,
            format!("/api/v1/admin/submissions/{id}"),
            413,
        )
        .by(As::Admin)
        .with(json, vec![b' '; 3 * 1024 * 1024]),
    ];
    assert!(cases.len() >= 40, "{} cases", cases.len());
    let mut failures = Vec::new();
    for c in cases {
        let mut call = server.call(c.method.clone(), &c.path);
        call = match c.who {
            As::Nobody => call,
            As::Submitter => call.bearer(&team),
            As::Admin => call.bearer(&admin),
        };
        if c.what == "a 300-character Idempotency-Key" {
            call = call.header("Idempotency-Key", &"k".repeat(300));
        }
        if let Some(t) = c.content_type {
            call = call.header("Content-Type", t);
        }
        let reply = call.body(c.body.clone()).send().await;
        let status = reply.status.as_u16();
        let error_body = serde_json::from_str::<serde_json::Value>(&reply.text)
            .ok()
            .and_then(|v| v["error"].as_str().map(str::to_owned));
        if status != c.status || error_body.is_none() {
            failures.push(format!(
                "{}: {} {} got {status}, expected {}: {}",
                c.what,
                c.method,
                &c.path[..c.path.len().min(80)],
                c.status,
                &reply.text[..reply.text.len().min(200)]
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} cases failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // Still alive and well.
    assert_eq!(server.get("/healthz").await.status(), 200);
    server.stop().await;
}
