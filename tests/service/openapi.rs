//! The OpenAPI document and its docs page: built from the route table the router is built
//! from, checked over HTTP so neither can drift from what is served.

use std::collections::BTreeSet;

use enact_hub::core::credentials::Role;
use enact_hub::web::api_routes;
use reqwest::Method;
use serde_json::{Value, json};

use crate::helpers::*;

async fn token(server: &TestServer, name: &str, role: Role) -> (i64, String) {
    api_token(&server.pool, name, role, None, None).await
}

const METHODS: [&str; 5] = ["get", "post", "put", "patch", "delete"];

#[tokio::test]
async fn every_api_route_is_documented_and_every_documented_route_answers() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin) = token(&server, "root", Role::Admin).await;
    let (throwaway, _) = token(&server, "team-a", Role::Submitter).await;

    // Real values for every path parameter, so no handler answers 404 for want of one.
    let item_id = records[0]["id"].as_str().expect("id").to_owned();
    let (_, item) = server
        .get_json(&format!("/api/v1/datasets/mini/items/{item_id}"))
        .await;
    let frame_url = item["images"][0]["url"].as_str().expect("url").to_owned();
    let sha256 = frame_url.rsplit('/').next().expect("hash").to_owned();
    let body: String = records
        .iter()
        .map(|r| json!({"id": r["id"], "answer": r["gt_answer"]}).to_string() + "\n")
        .collect();
    let created: Value = server
        .client
        .post(server.url("/api/v1/datasets/mini/submissions?model=m"))
        .bearer_auth(&admin)
        .body(body)
        .send()
        .await
        .expect("submit")
        .json()
        .await
        .expect("json");
    let submission = created["id"].as_i64().expect("id").to_string();

    let (status, doc) = server.get_json("/api/v1/openapi.json").await;
    assert_eq!(status, 200);
    assert_eq!(doc["openapi"], "3.1.0");
    let documented: BTreeSet<(String, String)> = doc["paths"]
        .as_object()
        .expect("paths")
        .iter()
        .flat_map(|(path, item)| {
            item.as_object()
                .expect("path item")
                .keys()
                .map(move |m| (m.to_ascii_uppercase(), path.clone()))
        })
        .collect();
    let mounted: BTreeSet<(String, String)> = api_routes()
        .iter()
        .map(|r| (r.verb.method().to_string(), r.full_path()))
        .collect();
    assert_eq!(
        documented, mounted,
        "the document lists exactly the mounted routes"
    );
    assert!(documented.len() >= 15, "{documented:?}");

    let reported = crate::authorization::reported_row(&server, 0)
        .await
        .to_string();
    crate::annotate::annotator(&server, "matrix-annotator", false).await;
    mini_study(&server, "kept").await;
    mini_study(&server, "doomed").await;
    // DELETE is tried first (the paths are sorted by method): it gets a study of its own.
    let fill = |method: &str, path: &str| {
        let study = if method == "DELETE" { "doomed" } else { "kept" };
        path.replace("{dataset}", "mini")
            .replace("{study}", study)
            .replace("{item_id}", &item_id)
            .replace("{sha256}", &sha256)
            .replace("{id}", &submission)
            .replace("{token_id_or_prefix}", &throwaway.to_string())
            .replace("{annotator}", "matrix-annotator")
            .replace("{model}", "m")
            .replace("{reported_id}", &reported)
    };
    // An item's answers are served only while its dataset's are public.
    set_mini_answers(
        &server.pool,
        enact_hub::core::dataset::AnswerVisibility::Public,
    )
    .await;
    for (method, path) in &documented {
        let url = server.url(&fill(method, path));
        let response = server
            .client
            .request(Method::from_bytes(method.as_bytes()).expect("method"), &url)
            .bearer_auth(&admin)
            .json(&json!({}))
            .send()
            .await
            .expect("request");
        let status = response.status().as_u16();
        assert!(
            status != 404 && status != 405,
            "{method} {path} answered {status}: {}",
            response.text().await.unwrap_or_default()
        );
    }
    // A method a path does not document is not served either.
    let paths: BTreeSet<&String> = documented.iter().map(|(_, p)| p).collect();
    for path in paths {
        for method in METHODS {
            let m = method.to_ascii_uppercase();
            if documented.contains(&(m.clone(), path.clone())) {
                continue;
            }
            let status = server
                .client
                .request(
                    Method::from_bytes(m.as_bytes()).expect("method"),
                    server.url(&fill(&m, path)),
                )
                .bearer_auth(&admin)
                .send()
                .await
                .expect("request")
                .status();
            assert_eq!(status, 405, "{m} {path} is served but not documented");
        }
    }
    // And the check can fail: an unknown route is 404.
    assert_eq!(server.get("/api/v1/no-such-route").await.status(), 404);
    server.stop().await;
}

#[tokio::test]
async fn the_document_covers_auth_bodies_parameters_and_errors() {
    let (server, _) = spawn_app_with_release().await;
    let (_, doc) = server.get_json("/api/v1/openapi.json").await;
    assert_eq!(
        doc["components"]["securitySchemes"]["bearer"]["scheme"],
        "bearer"
    );
    let error = &doc["components"]["schemas"]["Error"];
    assert_eq!(error["required"], json!(["error", "code"]));
    // Every code the hub answers with is listed: the kinds' and each typed reason's.
    let codes = error["properties"]["code"]["enum"]
        .as_array()
        .expect("the codes are listed");
    for code in [
        "not_found",
        "internal",
        "no_dataset",
        "item_finished",
        "slots_empty",
    ] {
        assert!(codes.contains(&json!(code)), "{code} is not listed");
    }
    assert!(error["properties"]["problems"]["items"]["properties"]["line"].is_object());

    let submit = &doc["paths"]["/api/v1/datasets/{dataset}/submissions"]["post"];
    assert_eq!(submit["security"], json!([{"bearer": []}]));
    for status in [
        "201", "200", "400", "401", "403", "404", "409", "413", "422", "429",
    ] {
        assert!(submit["responses"][status].is_object(), "missing {status}");
    }
    for status in ["401", "403", "404", "413", "422", "429"] {
        assert_eq!(
            submit["responses"][status]["content"]["application/json"]["schema"]["$ref"],
            "#/components/schemas/Error"
        );
    }
    assert!(
        submit["responses"]["429"]["description"]
            .as_str()
            .expect("text")
            .contains("Retry-After")
    );
    let params = submit["parameters"].as_array().expect("params");
    let param = |name: &str| {
        params
            .iter()
            .find(|p| p["name"] == name)
            .unwrap_or_else(|| panic!("no parameter {name}"))
    };
    assert_eq!(param("model")["required"], true);
    assert_eq!(param("model")["in"], "query");
    for name in ["description", "url", "prompt_version", "notes"] {
        assert_eq!(param(name)["required"], false);
    }
    assert_eq!(param("Idempotency-Key")["in"], "header");
    assert_eq!(param("dataset")["in"], "path");
    let body = &submit["requestBody"];
    assert_eq!(body["content"]["text/plain"]["schema"]["minLength"], 1);
    assert!(
        body["description"]
            .as_str()
            .expect("text")
            .contains("application/x-ndjson")
    );
    // Success bodies carry the schema of the Rust type the handler writes, JSON bodies the
    // schema of the type it reads, and parameters the values the server accepts.
    let schema_of = |response: &Value| {
        let reference = response["content"]["application/json"]["schema"]["$ref"]
            .as_str()
            .expect("a $ref");
        let name = reference.trim_start_matches("#/components/schemas/");
        doc["components"]["schemas"][name].clone()
    };
    let created = schema_of(&submit["responses"]["201"]);
    for field in ["id", "model", "scores", "visibility", "created_at"] {
        assert!(
            created["properties"][field].is_object(),
            "SubmissionView.{field}"
        );
    }
    let token = &doc["paths"]["/api/v1/admin/tokens"]["post"];
    let request = &token["requestBody"]["content"]["application/json"];
    assert_eq!(
        request["example"]["name"], "team-a",
        "the example is JSON, not a string"
    );
    let reference = request["schema"]["$ref"].as_str().expect("a $ref");
    let name = reference.trim_start_matches("#/components/schemas/");
    let request = &doc["components"]["schemas"][name];
    assert_eq!(request["required"], json!(["name"]));
    assert_eq!(request["additionalProperties"], false);
    assert!(token["responses"]["415"].is_object());
    let items = doc["paths"]["/api/v1/datasets/{dataset}/items"]["get"]["parameters"]
        .as_array()
        .expect("params");
    let per_page = items
        .iter()
        .find(|p| p["name"] == "per_page")
        .expect("per_page");
    assert_eq!(
        per_page["schema"]["anyOf"],
        json!([{"type": "integer", "minimum": 1, "maximum": 500}, {"const": ""}])
    );
    let public = &doc["paths"]["/api/v1/datasets"]["get"];
    assert_eq!(public["security"], json!([]));
    server.stop().await;
}

#[tokio::test]
async fn the_docs_page_renders_the_document_without_scripts_or_network() {
    let (server, _) = spawn_app_with_release().await;
    let home = server.get("/").await.text().await.expect("home");
    assert!(home.contains("href=\"/api/docs\""));
    let response = server.get("/api/docs").await;
    assert_eq!(response.status(), 200);
    let html = response.text().await.expect("page");
    assert!(!html.contains("<script"), "no JavaScript");
    assert!(
        !html.contains("src=\"http") && !html.contains("href=\"http"),
        "nothing loaded from elsewhere"
    );
    let (_, doc) = server.get_json("/api/v1/openapi.json").await;
    for (path, item) in doc["paths"].as_object().expect("paths") {
        for method in item.as_object().expect("item").keys() {
            let heading = format!("{} {}", method.to_ascii_uppercase(), path);
            assert!(html.contains(&heading), "the page lacks {heading}");
        }
    }
    assert!(html.contains("Bearer token with scope submit"));
    assert!(
        html.contains("<code>Retry-After</code>"),
        "code spans shown as code"
    );
    assert!(html.contains("application/x-ndjson"));
    assert!(html.contains("waiting will"));
    server.stop().await;
}

/// `schema` with its `$ref`s followed into the document's components.
fn resolved<'a>(doc: &'a Value, mut schema: &'a Value) -> &'a Value {
    while let Some(reference) = schema["$ref"].as_str() {
        let name = reference.trim_start_matches("#/components/schemas/");
        schema = &doc["components"]["schemas"][name];
    }
    schema
}

/// The schema an object in the body is read as: `schema` itself, or the branch of an
/// `anyOf`/`oneOf` that describes objects.
fn object_schema<'a>(doc: &'a Value, schema: &'a Value) -> Option<&'a Value> {
    let schema = resolved(doc, schema);
    if schema["type"] == "object" || schema["properties"].is_object() {
        return Some(schema);
    }
    ["anyOf", "oneOf"]
        .iter()
        .filter_map(|k| schema[*k].as_array())
        .flatten()
        .find_map(|branch| object_schema(doc, branch))
}

/// The schema of what `step` (a property name or an array index) leads to from `schema`.
fn child_schema<'a>(doc: &'a Value, schema: &'a Value, step: &str) -> Option<&'a Value> {
    if let Some(object) = object_schema(doc, schema) {
        return object["properties"].get(step);
    }
    let schema = resolved(doc, schema);
    let array = std::iter::once(schema)
        .chain(
            ["anyOf", "oneOf"]
                .iter()
                .filter_map(|k| schema[*k].as_array())
                .flatten()
                .map(|b| resolved(doc, b)),
        )
        .find(|s| s["type"] == "array")?;
    array.get("items")
}

/// The JSON pointer of every object in `value`, the root included.
fn object_pointers(value: &Value, at: String, out: &mut Vec<String>) {
    match value {
        Value::Object(fields) => {
            out.push(at.clone());
            for (k, v) in fields {
                object_pointers(v, format!("{at}/{k}"), out);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                object_pointers(v, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
}

/// `additionalProperties: false` in a request schema says the server refuses unknown fields
/// there, and its absence that it ignores them: every object of every JSON body's example is
/// sent with one unknown field added, and the refusal must match the schema both ways.
#[tokio::test]
async fn request_schemas_forbid_unknown_fields_exactly_where_the_server_refuses_them() {
    let (server, records) = spawn_app_with_release().await;
    let (_, admin) = token(&server, "root", Role::Admin).await;
    let submission = submit_to(&server, "mini", "model=m", &admin, answers(&records, &[]))
        .await
        .id()
        .to_string();
    let (_, doc) = server.get_json("/api/v1/openapi.json").await;

    let mut checked = 0;
    let mut forbidding = 0;
    for (path, item) in doc["paths"].as_object().expect("paths") {
        for (method, operation) in item.as_object().expect("path item") {
            let content = &operation["requestBody"]["content"]["application/json"];
            if content.is_null() {
                continue;
            }
            let example = &content["example"];
            let mut pointers = Vec::new();
            object_pointers(example, String::new(), &mut pointers);
            assert!(
                !pointers.is_empty(),
                "{method} {path}: no object in the example"
            );
            for pointer in pointers {
                let mut schema = &content["schema"];
                for step in pointer.split('/').skip(1) {
                    schema = child_schema(&doc, schema, step).unwrap_or_else(|| {
                        panic!("{method} {path}: the schema does not describe {pointer}")
                    });
                }
                let object = object_schema(&doc, schema)
                    .unwrap_or_else(|| panic!("{method} {path}: {pointer} is no object schema"));
                let forbids = object["additionalProperties"] == false;
                let mut body = example.clone();
                body.pointer_mut(&pointer)
                    .and_then(Value::as_object_mut)
                    .expect("an object")
                    .insert("zz_not_a_field".to_owned(), json!(1));
                let url = path
                    .trim_start_matches("/api/v1")
                    .replace("{dataset}", "mini")
                    .replace("{id}", &submission);
                let reply = server
                    .call(
                        Method::from_bytes(method.to_ascii_uppercase().as_bytes()).expect("verb"),
                        &format!("/api/v1{url}"),
                    )
                    .bearer(&admin)
                    .json(&body)
                    .send()
                    .await;
                let refused = reply.status == 422 && reply.text.contains("zz_not_a_field");
                assert_eq!(
                    forbids,
                    refused,
                    "{method} {path} at {pointer:?}: the schema {} unknown fields, the server \
                     answered {}: {}",
                    if forbids { "forbids" } else { "allows" },
                    reply.status,
                    reply.text
                );
                checked += 1;
                forbidding += usize::from(forbids);
            }
        }
    }
    // Four JSON bodies, one with variant objects inside; every one refuses unknown fields.
    assert!(checked >= 5, "{checked} objects checked");
    assert!(
        forbidding >= 5,
        "{forbidding} objects forbid unknown fields"
    );
    server.stop().await;
}
