//! The `/api/v1` route table, and the OpenAPI document and docs page built from it.
//!
//! Every JSON API route is an [`ApiRoute`]: its method, path, handler and documentation in one
//! value. The table itself is [`super::api_routes`]; [`api_router`] mounts exactly it and
//! [`document`] describes exactly it,
//! so a route cannot be served without being documented, nor documented with another method
//! than the one it answers to.

use std::sync::OnceLock;

use askama::Template;
use axum::Json;
use axum::Router;
use axum::handler::Handler;
use axum::http::Method;
use axum::middleware::from_fn_with_state;
use axum::response::Html;
use axum::routing::{MethodFilter, MethodRouter, get, on};
use schemars::generate::SchemaSettings;
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde_json::{Map, Value, json};

use super::auth::{ScopeGuard, require_scope};
use super::error::{ApiError, PageError, RenderPage};
use super::{AppError, AppState};
use crate::app::refusal::Refusal;
use crate::core::credentials::Scope;

/// Where the table is mounted.
pub const API_PREFIX: &str = "/api/v1";

/// The HTTP methods the API uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verb {
    Get,
    Post,
    Put,
    Patch,
    Delete,
}

impl Verb {
    pub fn method(self) -> Method {
        match self {
            Verb::Get => Method::GET,
            Verb::Post => Method::POST,
            Verb::Put => Method::PUT,
            Verb::Patch => Method::PATCH,
            Verb::Delete => Method::DELETE,
        }
    }

    fn filter(self) -> MethodFilter {
        match self {
            Verb::Get => MethodFilter::GET,
            Verb::Post => MethodFilter::POST,
            Verb::Put => MethodFilter::PUT,
            Verb::Patch => MethodFilter::PATCH,
            Verb::Delete => MethodFilter::DELETE,
        }
    }

    /// The key of an operation in an OpenAPI path item.
    fn key(self) -> &'static str {
        match self {
            Verb::Get => "get",
            Verb::Post => "post",
            Verb::Put => "put",
            Verb::Patch => "patch",
            Verb::Delete => "delete",
        }
    }
}

/// Who may call a route.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    Public,
    /// `Authorization: Bearer TOKEN` with this scope, checked by [`api_router`] before the
    /// handler runs.
    Bearer(Scope),
}

/// A query parameter or request header.
#[derive(Debug, Clone)]
pub struct Param {
    pub name: &'static str,
    /// `query` or `header`.
    pub location: &'static str,
    pub required: bool,
    pub description: &'static str,
    /// The values the server accepts, as JSON Schema: what a client may send without a 400.
    pub schema: Value,
}

/// A request body: its media types and what it holds.
#[derive(Debug, Clone)]
pub struct RequestBody {
    pub media_types: &'static [&'static str],
    pub description: &'static str,
    /// A JSON example, or the text of a non-JSON one.
    pub example: Option<&'static str>,
    /// The JSON Schema of a JSON body, from the Rust type the handler reads.
    pub schema: Option<SchemaFn>,
}

/// One documented response.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub status: u16,
    pub description: String,
    /// The media type of the body, if any.
    pub media_type: Option<&'static str>,
    /// The JSON Schema of the body, from the Rust type the handler serialises.
    pub schema: Option<SchemaFn>,
}

/// Adds a type's schema to a generator's definitions and returns a reference to it.
pub type SchemaFn = fn(&mut SchemaGenerator) -> Schema;

fn schema_of<T: JsonSchema>(generator: &mut SchemaGenerator) -> Schema {
    generator.subschema_for::<T>()
}

/// One route of the JSON API: what is mounted and what is documented, together.
pub struct ApiRoute {
    pub verb: Verb,
    /// Relative to [`API_PREFIX`], in axum's `{name}` syntax (which is OpenAPI's too).
    pub path: &'static str,
    pub summary: &'static str,
    pub description: &'static str,
    pub access: Access,
    pub params: Vec<Param>,
    pub body: Option<RequestBody>,
    pub outcomes: Vec<Outcome>,
    handler: MethodRouter<AppState>,
}

/// What an error status means on this API; every error body is the `Error` schema.
/// Every `code` an error body can carry: the kinds' and the typed reasons'.
fn error_codes() -> Vec<&'static str> {
    let mut codes = AppError::KIND_CODES.to_vec();
    codes.extend(Refusal::examples().iter().map(Refusal::code));
    codes
}

fn error_meaning(status: u16) -> &'static str {
    match status {
        400 => "A malformed request: a missing or invalid query parameter or body field.",
        401 => {
            "No valid API token: the `Authorization: Bearer TOKEN` header is missing, or the \
             token is unknown or revoked (`WWW-Authenticate: Bearer` is sent)."
        }
        403 => "The token lacks the scope this route needs.",
        404 => {
            "Nothing by that name or id (another account's submission is answered the same \
             way)."
        }
        409 => "A conflict with what is stored (see the message).",
        413 => "The body is larger than the server's limit for this route.",
        415 => "The body is not sent as `Content-Type: application/json`.",
        422 => {
            "The body was read but refused; nothing was stored. `problems` lists each bad \
             line: its 1-based number, a `kind` (empty_body, invalid_json, not_an_object, \
             missing_id, unknown_id, duplicate_id, missing_answer, malformed_answer), the item \
             id when known, and a message."
        }
        429 => {
            "A quota is used up. Past the daily quota, `Retry-After` gives the seconds to the \
             next UTC midnight; past the total quota there is no `Retry-After`: waiting will \
             not help."
        }
        _ => "An error; see the message.",
    }
}

impl ApiRoute {
    pub fn new<H, T>(verb: Verb, path: &'static str, handler: H, summary: &'static str) -> Self
    where
        H: Handler<T, AppState>,
        T: 'static,
    {
        ApiRoute {
            verb,
            path,
            summary,
            description: "",
            access: Access::Public,
            params: Vec::new(),
            body: None,
            outcomes: Vec::new(),
            handler: on(verb.filter(), handler),
        }
    }

    pub fn describe(mut self, description: &'static str) -> Self {
        self.description = description;
        self
    }

    pub fn bearer(mut self, scope: Scope) -> Self {
        self.access = Access::Bearer(scope);
        self
    }

    pub fn query(mut self, name: &'static str, required: bool, description: &'static str) -> Self {
        self.params.push(Param {
            name,
            location: "query",
            required,
            description,
            schema: json!({"type": "string"}),
        });
        self
    }

    /// A query parameter whose accepted values `schema` describes (a range, a list, a pattern).
    pub fn query_with(
        mut self,
        name: &'static str,
        required: bool,
        schema: Value,
        description: &'static str,
    ) -> Self {
        self.params.push(Param {
            name,
            location: "query",
            required,
            description,
            schema,
        });
        self
    }

    pub fn header(mut self, name: &'static str, schema: Value, description: &'static str) -> Self {
        self.params.push(Param {
            name,
            location: "header",
            required: false,
            description,
            schema,
        });
        self
    }

    pub fn body(
        mut self,
        media_types: &'static [&'static str],
        description: &'static str,
        example: Option<&'static str>,
    ) -> Self {
        self.body = Some(RequestBody {
            media_types,
            description,
            example,
            schema: None,
        });
        self
    }

    /// A JSON body read as a `T`, documented with `T`'s schema; `example` is JSON text.
    pub fn body_json<T: JsonSchema>(
        mut self,
        description: &'static str,
        example: &'static str,
    ) -> Self {
        self.body = Some(RequestBody {
            media_types: &["application/json"],
            description,
            example: Some(example),
            schema: Some(schema_of::<T>),
        });
        self
    }

    /// A success (or other non-error) response without a JSON body.
    pub fn responds(
        mut self,
        status: u16,
        media_type: Option<&'static str>,
        description: &'static str,
    ) -> Self {
        self.outcomes.push(Outcome {
            status,
            description: description.to_owned(),
            media_type,
            schema: None,
        });
        self
    }

    /// A success response whose JSON body is a `T`, documented with `T`'s schema.
    pub fn responds_json<T: JsonSchema>(mut self, status: u16, description: &'static str) -> Self {
        self.outcomes.push(Outcome {
            status,
            description: description.to_owned(),
            media_type: Some("application/json"),
            schema: Some(schema_of::<T>),
        });
        self
    }

    /// Error responses, with this API's standard meaning for each status.
    pub fn errors(mut self, statuses: &[u16]) -> Self {
        for &status in statuses {
            self.outcomes.push(Outcome {
                status,
                description: error_meaning(status).to_owned(),
                media_type: Some("application/json"),
                schema: None,
            });
        }
        self
    }

    /// The path as clients call it.
    pub fn full_path(&self) -> String {
        format!("{API_PREFIX}{}", self.path)
    }

    /// The names of the path's `{parameters}`, in order.
    pub fn path_params(&self) -> Vec<&'static str> {
        self.path
            .split('/')
            .filter_map(|s| s.strip_prefix('{').and_then(|s| s.strip_suffix('}')))
            .collect()
    }
}

/// The router of exactly the routes in `routes` (to be nested under [`API_PREFIX`]), each
/// behind the check its [`Access`] names.
pub fn api_router(routes: Vec<ApiRoute>, state: &AppState) -> Router<AppState> {
    // Two methods on one path merge into one method router; a method given twice panics at
    // start-up, which the test suite would show.
    routes
        .into_iter()
        .fold(Router::new(), |router, r| {
            let handler = match r.access {
                Access::Public => r.handler,
                // A layer runs before the handler's extractors, so a caller without the right
                // hears 401 or 403 before any of the body is read, whatever the body holds.
                Access::Bearer(scope) => r.handler.route_layer(from_fn_with_state(
                    ScopeGuard {
                        state: state.clone(),
                        scope,
                    },
                    require_scope,
                )),
            };
            router.route(r.path, handler)
        })
        .fallback(unknown_route)
}

/// A path under `/api/v1` that no route serves: the JSON error body, like every refusal.
async fn unknown_route(uri: axum::http::Uri) -> ApiError {
    Refusal::NoApiRoute {
        path: uri.path().to_owned(),
    }
    .into()
}

/// The HTML docs page, outside `/api/v1`.
pub fn page_router() -> Router<AppState> {
    Router::new().route("/api/docs", get(docs_page))
}

fn path_param_description(name: &str) -> &'static str {
    match name {
        "dataset" => "Dataset name, as listed by GET /api/v1/datasets.",
        "item_id" => "ENACT item id within the dataset.",
        "sha256" => "The frame's SHA-256, 64 lowercase hex digits (from an item's image URLs).",
        "id" => "Submission id, as returned when it was posted.",
        // Not `token`: the secret a client holds is not what revokes it.
        "token_id_or_prefix" => "A token's id or its public prefix (never its secret).",
        "run" => "A model run's id, as returned when it was started.",
        "job" => "A background job's id, as returned when it was queued.",
        "change" => "`pause`, `resume` or `cancel`.",
        _ => "Path parameter.",
    }
}

/// The values a path parameter takes. A number is an id the handler reads as an `i64`, so the
/// document says so (a schemathesis run found `/admin/runs/abc` answered with an undocumented
/// 400 when every path parameter was documented as any string).
fn path_param_schema(name: &str) -> Value {
    match name {
        "run" | "job" | "reported_id" => {
            json!({"type": "integer", "minimum": 1, "maximum": i64::MAX})
        }
        "change" => json!({"enum": ["pause", "resume", "cancel"]}),
        _ => json!({"type": "string", "minLength": 1}),
    }
}

fn parameter_json(
    name: &str,
    location: &str,
    required: bool,
    description: &str,
    schema: &Value,
) -> Value {
    json!({
        "name": name,
        "in": location,
        "required": required,
        "description": description,
        "schema": schema,
    })
}

fn operation_json(
    route: &ApiRoute,
    generator: &mut SchemaGenerator,
    requests: &mut SchemaGenerator,
) -> Value {
    let mut parameters: Vec<Value> = route
        .path_params()
        .into_iter()
        .map(|p| {
            parameter_json(
                p,
                "path",
                true,
                path_param_description(p),
                &path_param_schema(p),
            )
        })
        .collect();
    parameters.extend(
        route
            .params
            .iter()
            .map(|p| parameter_json(p.name, p.location, p.required, p.description, &p.schema)),
    );
    let mut responses = Map::new();
    for outcome in &route.outcomes {
        let mut response = json!({"description": outcome.description});
        if let Some(media) = outcome.media_type {
            let schema = if outcome.status >= 400 {
                json!({"$ref": "#/components/schemas/Error"})
            } else if let Some(schema) = outcome.schema {
                schema(generator).to_value()
            } else if media == "application/json" {
                json!({"type": "object"})
            } else {
                json!({"type": "string", "format": "binary"})
            };
            response["content"] = json!({ media: {"schema": schema} });
        }
        // A status given twice answers in either media type (JSON, or CSV when asked).
        if let Some(Value::Object(earlier)) = responses.get_mut(&outcome.status.to_string()) {
            if let (Some(Value::Object(content)), Some(Value::Object(more))) =
                (earlier.get_mut("content"), response.get("content"))
            {
                content.extend(more.clone());
            }
            continue;
        }
        responses.insert(outcome.status.to_string(), response);
    }
    let mut operation = json!({
        "operationId": format!("{}{}", route.verb.key(), route.path.replace(['/', '{', '}'], "_")),
        "summary": route.summary,
        "description": route.description,
        "parameters": parameters,
        "responses": responses,
    });
    match route.access {
        Access::Public => operation["security"] = json!([]),
        Access::Bearer(scope) => {
            operation["security"] = json!([{"bearer": []}]);
            operation["x-scope"] = json!(scope.as_str());
        }
    }
    if let Some(body) = &route.body {
        let mut content = Map::new();
        for media in body.media_types {
            let mut entry = match body.schema {
                Some(schema) => json!({"schema": schema(requests).to_value()}),
                None => json!({"schema": {"type": "string", "minLength": 1}}),
            };
            if let Some(example) = body.example {
                entry["example"] = match body.schema {
                    Some(_) => serde_json::from_str(example).expect("a JSON example"),
                    None => json!(example),
                };
            }
            content.insert((*media).to_owned(), entry);
        }
        operation["requestBody"] = json!({
            "required": true,
            "description": body.description,
            "content": content,
        });
    }
    operation
}

/// The OpenAPI 3.1 document of `routes`.
pub fn document(routes: &[ApiRoute]) -> Value {
    // Response and request types' schemas become components that operations refer to; a
    // response is described as it is written, a request as it is read (optional fields).
    let settings = SchemaSettings::draft2020_12().with(|s| {
        s.definitions_path = "/components/schemas".into();
        s.meta_schema = None;
    });
    let mut generator = settings.clone().for_serialize().into_generator();
    let mut requests = settings.for_deserialize().into_generator();
    let mut paths = Map::new();
    for route in routes {
        let item = paths
            .entry(route.full_path())
            .or_insert_with(|| Value::Object(Map::new()));
        item[route.verb.key()] = operation_json(route, &mut generator, &mut requests);
    }
    let mut document = json!({
        "openapi": "3.1.0",
        "info": {
            "title": "enact-hub API",
            "version": env!("CARGO_PKG_VERSION"),
            "description": "Datasets of the ENACT benchmark, their items and frames, model \
                submissions with their scores, and the leaderboard. Reading datasets is public; \
                submitting and administration need an API token sent as \
                `Authorization: Bearer TOKEN` (tokens come from an admin: `enact-hub token \
                create`, or the /admin/tokens page). Every error is JSON of the Error schema.",
        },
        "paths": paths,
        "components": {
            "securitySchemes": {
                "bearer": {
                    "type": "http",
                    "scheme": "bearer",
                    "description": "An enact-hub API token. Submitter tokens have the scopes \
                        submit and read_own; admin tokens also have admin.",
                },
            },
            "schemas": {
                "Error": {
                    "type": "object",
                    "required": ["error", "code"],
                    "properties": {
                        "error": {"type": "string", "description": "What was wrong, for a person to act on (English)."},
                        "code": {
                            "type": "string",
                            "enum": error_codes(),
                            "description": "What was wrong, for a program to branch on; stable across \
                                versions. A typed reason's own code (`no_item`, `item_finished`, ...), \
                                or, for a refusal not yet typed, its kind's (`not_found`, `invalid`, ...).",
                        },
                        "details": {
                            "type": "object",
                            "description": "A typed reason only: the values it names (`dataset`, `item`, \
                                `limit`, ...), as strings or numbers.",
                            "additionalProperties": {"type": ["string", "integer"]},
                        },
                        "problems": {
                            "type": "array",
                            "description": "422 only: each refused line of the body.",
                            "items": {
                                "type": "object",
                                "required": ["line", "kind", "message"],
                                "properties": {
                                    "line": {"type": "integer", "description": "1-based line (JSONL) or element (JSON array)."},
                                    "kind": {"type": "string", "enum": ["empty_body", "invalid_json", "not_an_object", "missing_id", "unknown_id", "duplicate_id", "missing_answer", "malformed_answer"]},
                                    "item": {"type": "string", "description": "The item id, when the line named one."},
                                    "message": {"type": "string"},
                                },
                            },
                        },
                    },
                },
            },
        },
    });
    let schemas = document["components"]["schemas"]
        .as_object_mut()
        .expect("the document has components.schemas");
    schemas.extend(generator.take_definitions(true));
    schemas.extend(requests.take_definitions(true));
    document
}

/// The document never changes while the server runs: build it once.
fn cached_document() -> &'static Value {
    static DOCUMENT: OnceLock<Value> = OnceLock::new();
    DOCUMENT.get_or_init(|| document(&super::api_routes()))
}

pub(super) async fn openapi_json() -> Json<Value> {
    Json(cached_document().clone())
}

/// A piece of a description: descriptions are CommonMark, and the page shows their
/// `code spans` as code (the only markup they use).
struct Span {
    code: bool,
    text: String,
}

fn spans(description: &str) -> Vec<Span> {
    description
        .split('`')
        .enumerate()
        .filter(|(_, t)| !t.is_empty())
        .map(|(i, t)| Span {
            code: i % 2 == 1,
            text: t.to_owned(),
        })
        .collect()
}

struct ParamView {
    name: String,
    location: String,
    required: bool,
    description: Vec<Span>,
}

struct ResponseView {
    status: String,
    media_type: String,
    description: Vec<Span>,
}

struct OperationView {
    anchor: String,
    method: String,
    path: String,
    summary: String,
    description: Vec<Span>,
    auth: String,
    params: Vec<ParamView>,
    body_types: Vec<String>,
    body_description: Vec<Span>,
    body_example: Option<String>,
    responses: Vec<ResponseView>,
}

#[derive(Template)]
#[template(path = "api_docs.html")]
struct DocsPage {
    title: String,
    version: String,
    description: Vec<Span>,
    operations: Vec<OperationView>,
}

fn text(v: &Value) -> String {
    v.as_str().unwrap_or_default().to_owned()
}

/// Reads the operations back out of the document, so the page shows what the document says.
fn operations(doc: &Value) -> Vec<OperationView> {
    let mut out = Vec::new();
    let Some(paths) = doc["paths"].as_object() else {
        return out;
    };
    for (path, item) in paths {
        let Some(item) = item.as_object() else {
            continue;
        };
        for (method, op) in item {
            let auth = match op["security"].as_array().map(Vec::len) {
                Some(0) | None => "none (public)".to_owned(),
                _ => format!("Bearer token with scope {}", text(&op["x-scope"])),
            };
            let body = &op["requestBody"];
            let body_types: Vec<String> = body["content"]
                .as_object()
                .map(|c| c.keys().cloned().collect())
                .unwrap_or_default();
            let body_example = body["content"]
                .as_object()
                .and_then(|c| c.values().find_map(|m| m["example"].as_str()))
                .map(str::to_owned);
            out.push(OperationView {
                anchor: text(&op["operationId"]),
                method: method.to_ascii_uppercase(),
                path: path.clone(),
                summary: text(&op["summary"]),
                description: spans(&text(&op["description"])),
                auth,
                params: op["parameters"]
                    .as_array()
                    .map(|ps| {
                        ps.iter()
                            .map(|p| ParamView {
                                name: text(&p["name"]),
                                location: text(&p["in"]),
                                required: p["required"].as_bool().unwrap_or(false),
                                description: spans(&text(&p["description"])),
                            })
                            .collect()
                    })
                    .unwrap_or_default(),
                body_types,
                body_description: spans(&text(&body["description"])),
                body_example,
                responses: op["responses"]
                    .as_object()
                    .map(|rs| {
                        rs.iter()
                            .map(|(status, r)| ResponseView {
                                status: status.clone(),
                                media_type: r["content"]
                                    .as_object()
                                    .and_then(|c| c.keys().next().cloned())
                                    .unwrap_or_default(),
                                description: spans(&text(&r["description"])),
                            })
                            .collect()
                    })
                    .unwrap_or_default(),
            });
        }
    }
    out
}

async fn docs_page() -> Result<Html<String>, PageError> {
    let doc = cached_document();
    let page = DocsPage {
        title: text(&doc["info"]["title"]),
        version: text(&doc["info"]["version"]),
        description: spans(&text(&doc["info"]["description"])),
        operations: operations(doc),
    };
    Ok(Html(page.render_page()?))
}
