//! The authorization matrix of the JSON API: every route of the route table (the one the router
//! and the OpenAPI document are built from) × every kind of caller, with the status each must
//! get. A route the table below does not know fails the test, so no new route is left out.

use enact_hub::core::credentials::Role;
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
}

const CALLERS: [Caller; 6] = [
    Caller::Anonymous,
    Caller::Malformed,
    Caller::Revoked,
    Caller::Owner,
    Caller::Stranger,
    Caller::Admin,
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
        Caller::Anonymous | Caller::Malformed | Caller::Revoked => Expected::Status(401),
        Caller::Admin => Expected::Success,
        Caller::Owner | Caller::Stranger if scope == "admin" => Expected::Status(403),
        // Another account's submission is answered like a missing one.
        Caller::Stranger if path.contains("/submissions/{id}") => Expected::Status(404),
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
        (Verb::Delete, "/admin/tokens/{token}") => Some((String::new(), "text/plain")),
        (verb, path) => {
            panic!("the authorization matrix has no request for {verb:?} {path}: add it to body_of")
        }
    }
}

fn method(verb: Verb) -> Method {
    verb.method()
}

#[tokio::test]
async fn every_api_route_answers_every_caller_as_the_matrix_says() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin) = api_token(&server.pool, "root", Role::Admin, None, None).await;
    let (_, owner) = api_token(&server.pool, "team", Role::Submitter, None, None).await;
    let (_, stranger) = api_token(&server.pool, "other", Role::Submitter, None, None).await;
    let (revoked_id, revoked) = api_token(&server.pool, "gone", Role::Submitter, None, None).await;
    server
        .call(
            Method::DELETE,
            &format!("/api/v1/admin/tokens/{revoked_id}"),
        )
        .bearer(&admin)
        .expect(204)
        .await;
    let submission = {
        let reply = submit_to(&server, "mini", "model=m", &owner, answers(&records, &[])).await;
        assert_eq!(reply.status, 201, "{}", reply.text);
        reply.id()
    };
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
                    "token" => {
                        api_token(&server.pool, &format!("t{n}"), Role::Submitter, None, None)
                            .await
                            .0
                            .to_string()
                    }
                    other => panic!(
                        "the authorization matrix cannot fill {{{other}}} in {}",
                        route.path
                    ),
                };
                path = path.replace(&format!("{{{param}}}"), &value);
            }
            // The one required query parameter among the routes: a submission's model.
            if route.path == "/datasets/{dataset}/submissions" {
                path.push_str("?model=matrix");
            }
            let mut call = server.call(method(route.verb), &format!("/api/v1{path}"));
            call = match caller {
                Caller::Anonymous => call,
                Caller::Malformed => call.header("Authorization", "Bearer not-a-token"),
                Caller::Revoked => call.bearer(&revoked),
                Caller::Owner => call.bearer(&owner),
                Caller::Stranger => call.bearer(&stranger),
                Caller::Admin => call.bearer(&admin),
            };
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
