//! The architecture, checked where Cargo cannot: reads every `crate::`, `super::` and `self::`
//! path in `src/` and fails when the command line reaches past the use cases into the store, and
//! in `src/` and the crates' sources when sibling modules use each other in a cycle.
//!
//! Layers, bottom to top: `core` (pure benchmark logic, the `enact-core` crate), `store` (rows,
//! the `enact-store` crate), the service kit (`Hub` and what every use case shares, the
//! `enact-service` crate, which names no use case, and beside it the outbound clients,
//! `enact-outbound`), `app` (use cases, the `enact-app` crate) and `web` (the HTTP service, the
//! `enact-web` crate, which does not depend on enact-store), which Cargo keeps from naming any
//! layer above them; then, in this crate, the command line `cli`. The hub names the four crates
//! `crate::core`, `crate::store`, `crate::app` and `crate::web`. Each area of this crate may use
//! only what is listed for it in [`ALLOWED`].

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Which top-level areas each area may use.
const ALLOWED: &[(&str, &[&str])] = &[("cli", &["core", "app", "web"])];

/// A module path below the crate root: `["core", "verifier", "answer"]`.
type ModulePath = Vec<String>;

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            source_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module a file defines: `src/app/runs/mod.rs` is `app::runs`.
fn module_of(src: &Path, file: &Path) -> ModulePath {
    let relative = file.strip_prefix(src).expect("file under src");
    let mut parts: Vec<String> = relative
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_owned());
    }
    parts
}

/// The text with comments, string and character literals blanked out, so that prose and
/// strings mentioning `crate::…` do not count.
fn code_only(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        let rest = &text[i..];
        if rest.starts_with("//") {
            let end = rest.find('\n').unwrap_or(rest.len());
            i += end;
        } else if rest.starts_with("/*") {
            let end = rest.find("*/").map_or(rest.len(), |e| e + 2);
            i += end;
            out.push(' ');
        } else if let Some(raw) = rest.strip_prefix("r#\"") {
            let end = raw.find("\"#").map_or(rest.len(), |e| e + 5);
            i += end;
            out.push_str("\"\"");
        } else if rest.starts_with('"') {
            let mut j = 1;
            while j < rest.len() {
                match rest.as_bytes()[j] {
                    b'\\' => j += 2,
                    b'"' => break,
                    _ => j += 1,
                }
            }
            i += (j + 1).min(rest.len());
            out.push_str("\"\"");
        } else if rest.starts_with('\'') && rest.len() >= 3 && {
            // A character literal ('a', '\n', '\''), not a lifetime ('a).
            let b = rest.as_bytes();
            b[1] == b'\\' || b.get(2) == Some(&b'\'')
        } {
            let end = if rest.as_bytes()[1] == b'\\' {
                rest[2..].find('\'').map_or(rest.len(), |e| e + 3)
            } else {
                3
            };
            i += end;
            out.push_str("' '");
        } else {
            let c = rest.chars().next().expect("not empty");
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

/// Expands a use tree (`crate::a::{b, c::{d, e}}`) into its paths.
fn expand_use_tree(tree: &str) -> Vec<String> {
    let tree: String = tree.split_whitespace().collect();
    let Some(open) = tree.find('{') else {
        return vec![tree];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| expand_use_tree(&format!("{prefix}{p}")))
        .collect()
}

/// Where the path that starts at `at` ends, or `None` when `at` is inside a longer name.
fn path_end(bytes: &[u8], at: usize) -> Option<usize> {
    if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
        return None;
    }
    let mut end = at;
    while end < bytes.len()
        && (bytes[end].is_ascii_alphanumeric() || bytes[end] == b'_' || bytes[end] == b':')
    {
        end += 1;
    }
    Some(end)
}

/// Every path that starts with `crate`, `super` or `self`, as written.
fn referenced_paths(code: &str) -> Vec<String> {
    let mut paths = Vec::new();
    // `use` declarations, braces expanded.
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let boundary = at == 0 || !rest.as_bytes()[at - 1].is_ascii_alphanumeric();
        let after = &rest[at + 4..];
        if boundary && let Some(end) = after.find(';') {
            let tree = &after[..end];
            if tree.trim_start().starts_with("crate::")
                || tree.trim_start().starts_with("super::")
                || tree.trim_start().starts_with("self::")
            {
                paths.extend(expand_use_tree(tree));
            }
        }
        rest = &rest[at + 4..];
    }
    // Paths written inline in code.
    let bytes = code.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(at) = code[from..].find(start) {
            let at = from + at;
            from = at + start.len();
            if let Some(end) = path_end(bytes, at) {
                paths.push(code[at..end].trim_end_matches(':').to_owned());
            }
        }
    }
    paths
}

/// The module a path names, as the longest known module prefix of its resolved form.
fn resolve(path: &str, from: &ModulePath, known: &BTreeSet<ModulePath>) -> Option<ModulePath> {
    let mut segments = path.split("::").filter(|s| !s.is_empty());
    let mut base: ModulePath = match segments.next()? {
        "crate" => Vec::new(),
        "self" => from.clone(),
        "super" => {
            let mut b = from.clone();
            b.pop();
            b
        }
        _ => return None,
    };
    for segment in segments {
        if segment == "super" {
            base.pop();
        } else {
            base.push(segment.to_owned());
        }
    }
    while !base.is_empty() && !known.contains(&base) {
        base.pop();
    }
    Some(base)
}

struct Graph {
    /// (from module, to module) for every reference across modules.
    edges: BTreeSet<(ModulePath, ModulePath)>,
    /// Where each edge was seen first, for the failure message.
    witness: BTreeMap<(ModulePath, ModulePath), String>,
}

/// The hub crate's own sources (`src/`); the lower crates' are [`crate_srcs`]'s.
fn hub_src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The lower crates' sources: Cargo keeps those crates from naming the layers above them, but
/// not their own modules from using each other in a cycle.
fn crate_srcs() -> [PathBuf; 6] {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        root.join("crates/enact-core/src"),
        root.join("crates/enact-store/src"),
        root.join("crates/enact-service/src"),
        root.join("crates/enact-outbound/src"),
        root.join("crates/enact-app/src"),
        root.join("crates/enact-web/src"),
    ]
}

/// The crates the hub re-exports at its root (`pub use enact_store as store;`): a path into them
/// is a use of that layer, though no file in `src/` defines it.
const REEXPORTED: [&str; 4] = ["core", "store", "app", "web"];

fn build_graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    source_files(src, &mut files);
    let modules: Vec<(PathBuf, ModulePath)> = files
        .iter()
        .map(|f| (f.clone(), module_of(src, f)))
        .collect();
    let known: BTreeSet<ModulePath> = modules
        .iter()
        .map(|(_, m)| m.clone())
        .chain(REEXPORTED.iter().map(|name| vec![(*name).to_owned()]))
        .collect();
    let mut edges = BTreeSet::new();
    let mut witness = BTreeMap::new();
    for (file, module) in &modules {
        let text = std::fs::read_to_string(file).expect("readable source");
        for path in referenced_paths(&code_only(&text)) {
            let Some(target) = resolve(&path, module, &known) else {
                continue;
            };
            if target != *module && !target.is_empty() {
                let edge = (module.clone(), target);
                witness.entry(edge.clone()).or_insert_with(|| {
                    format!(
                        "{} uses `{path}`",
                        file.strip_prefix(src).unwrap_or(file).display()
                    )
                });
                edges.insert(edge);
            }
        }
    }
    Graph { edges, witness }
}

/// The child of `parent` that `module` lies in, if it lies strictly below `parent`.
fn child_under(parent: &[String], module: &[String]) -> Option<String> {
    (module.len() > parent.len() && module.starts_with(parent))
        .then(|| module[parent.len()].clone())
}

/// Strongly connected components with more than one member (Tarjan's algorithm).
fn cycles(nodes: &BTreeSet<String>, edges: &BTreeSet<(String, String)>) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a BTreeSet<(String, String)>,
        index: BTreeMap<String, usize>,
        low: BTreeMap<String, usize>,
        stack: Vec<String>,
        on_stack: BTreeSet<String>,
        next: usize,
        found: Vec<Vec<String>>,
    }
    fn visit(s: &mut State<'_>, v: &str) {
        s.index.insert(v.to_owned(), s.next);
        s.low.insert(v.to_owned(), s.next);
        s.next += 1;
        s.stack.push(v.to_owned());
        s.on_stack.insert(v.to_owned());
        let targets: Vec<String> = s
            .edges
            .iter()
            .filter(|(a, _)| a == v)
            .map(|(_, b)| b.clone())
            .collect();
        for w in targets {
            if !s.index.contains_key(&w) {
                visit(s, &w);
                let low = s.low[v].min(s.low[&w]);
                s.low.insert(v.to_owned(), low);
            } else if s.on_stack.contains(&w) {
                let low = s.low[v].min(s.index[&w]);
                s.low.insert(v.to_owned(), low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(&w);
                let done = w == v;
                component.push(w);
                if done {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.found.push(component);
            }
        }
    }
    let mut state = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        next: 0,
        found: Vec::new(),
    };
    for n in nodes {
        if !state.index.contains_key(n) {
            visit(&mut state, n);
        }
    }
    state.found
}

#[test]
fn layers_only_use_the_layers_below_them() {
    let graph = build_graph(&hub_src());
    let allowed: BTreeMap<&str, &[&str]> = ALLOWED.iter().copied().collect();
    let mut violations = Vec::new();
    for (edge, how) in &graph.witness {
        let (from, to) = (&edge.0[0], &edge.1[0]);
        if from == to {
            continue;
        }
        match allowed.get(from.as_str()) {
            Some(may) if may.contains(&to.as_str()) => {}
            Some(_) => violations.push(format!("{from} may not use {to}: {how}")),
            None => violations.push(format!(
                "top-level module `{from}` is in no layer (add it to ALLOWED): {how}"
            )),
        }
    }
    assert!(
        violations.is_empty(),
        "layering violations:\n{}",
        violations.join("\n")
    );
}

#[test]
fn sibling_modules_never_use_each_other_in_a_cycle() {
    for src in std::iter::once(hub_src()).chain(crate_srcs()) {
        assert_no_cycles(&build_graph(&src), &src);
    }
}

fn assert_no_cycles(graph: &Graph, src: &Path) {
    let parents: BTreeSet<ModulePath> = graph
        .edges
        .iter()
        .flat_map(|(a, b)| [a, b])
        .flat_map(|m| (0..m.len()).map(move |k| m[..k].to_vec()))
        .collect();
    let mut found = Vec::new();
    for parent in &parents {
        let mut nodes = BTreeSet::new();
        let mut edges = BTreeSet::new();
        for (a, b) in &graph.edges {
            if let (Some(x), Some(y)) = (child_under(parent, a), child_under(parent, b))
                && x != y
            {
                nodes.insert(x.clone());
                nodes.insert(y.clone());
                edges.insert((x, y));
            }
        }
        for cycle in cycles(&nodes, &edges) {
            let within = if parent.is_empty() {
                "crate".to_owned()
            } else {
                parent.join("::")
            };
            let examples: Vec<String> = graph
                .witness
                .iter()
                .filter(|((a, b), _)| {
                    matches!((child_under(parent, a), child_under(parent, b)),
                        (Some(x), Some(y)) if x != y && cycle.contains(&x) && cycle.contains(&y))
                })
                .map(|(_, how)| format!("    {how}"))
                .collect();
            found.push(format!(
                "cycle in {within} between {}:\n{}",
                cycle.join(", "),
                examples.join("\n")
            ));
        }
    }
    assert!(
        found.is_empty(),
        "module cycles in {}:\n{}",
        src.display(),
        found.join("\n")
    );
}

#[test]
fn the_checker_sees_paths_in_every_form() {
    let code = code_only(
        "use crate::core::{dataset::X, verifier::{a, b}};\n// crate::web in a comment\n\
         let s = \"crate::cli in a string\"; let c = '\"'; fn f() { crate::store::open(); }\n\
         use super::sibling;",
    );
    let paths = referenced_paths(&code);
    for expected in [
        "crate::core::dataset::X",
        "crate::core::verifier::a",
        "crate::core::verifier::b",
        "crate::store::open",
        "super::sibling",
    ] {
        assert!(
            paths.iter().any(|p| p == expected),
            "{expected} not in {paths:?}"
        );
    }
    assert!(!paths.iter().any(|p| p.contains("web") || p.contains("cli")));
    let known: BTreeSet<ModulePath> = [vec!["core".to_owned()], vec!["store".to_owned()]]
        .into_iter()
        .collect();
    let from = vec!["app".to_owned(), "import".to_owned()];
    assert_eq!(
        resolve("crate::store::items::get", &from, &known),
        Some(vec!["store".to_owned()])
    );
    let mut edges = BTreeSet::new();
    edges.insert(("a".to_owned(), "b".to_owned()));
    edges.insert(("b".to_owned(), "a".to_owned()));
    edges.insert(("b".to_owned(), "c".to_owned()));
    let nodes = ["a", "b", "c"].iter().map(|s| (*s).to_owned()).collect();
    assert_eq!(
        cycles(&nodes, &edges),
        vec![vec!["a".to_owned(), "b".to_owned()]]
    );
}

/// The last segment of a path names a type (`UpperCamel`) or a constant (`UPPER_SNAKE`), not a
/// function or a module.
fn names_a_type_or_constant(path: &str) -> bool {
    let last = path.rsplit("::").next().unwrap_or("");
    last.chars().next().is_some_and(|c| c.is_ascii_uppercase())
}

/// Every path into the core in `code` (`start` is `crate::core::` in the hub, `enact_core::` in
/// enact-store), use trees expanded into their branches (a tree's prefix is not itself a use of
/// the module).
fn core_paths(code: &str, start: &str) -> Vec<String> {
    let bytes = code.as_bytes();
    let mut paths = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..].find(start) {
        let at = from + at;
        from = at + start.len();
        let Some(end) = path_end(bytes, at) else {
            continue;
        };
        if bytes.get(end) == Some(&b'!') {
            // A macro of the core's (`enact_core::text_columns!`), which makes code, not calls.
            continue;
        }
        if bytes.get(end) == Some(&b'{') {
            let mut depth = 0;
            let mut close = end;
            for (i, &b) in bytes.iter().enumerate().skip(end) {
                match b {
                    b'{' => depth += 1,
                    b'}' => depth -= 1,
                    _ => {}
                }
                if depth == 0 {
                    close = i;
                    break;
                }
            }
            paths.extend(expand_use_tree(&code[at..=close]));
            from = close;
        } else {
            paths.push(code[at..end].trim_end_matches(':').to_owned());
        }
    }
    paths
}

/// Every path into the core (starting with `start`) used by the files under `dir` (relative to
/// the workspace) whose last segment is neither a type nor a constant nor in `allowed`, with the
/// file it is in.
fn core_calls_in(dir: &str, start: &str, allowed: &[&str]) -> Vec<String> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    source_files(&src.join(dir), &mut files);
    let mut found = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).expect("readable source");
        for path in core_paths(&code_only(&text), start) {
            let Some(inside) = path.strip_prefix(start) else {
                continue;
            };
            if !names_a_type_or_constant(&path) && !allowed.contains(&inside) {
                found.push(format!(
                    "{} uses `{path}`",
                    file.strip_prefix(src).unwrap_or(&file).display()
                ));
            }
        }
    }
    found
}

/// The command line does no work of its own: it names the core's types and constants (to
/// parse arguments and print results) and calls only these formatting functions of the core;
/// scoring, analysing, generating and simulating are use cases in `app` that it calls.
const CLI_MAY_CALL: &[&str] = &[
    "error_analysis::present::text_table",
    "scoring::performance_table",
    "study::figure::p_text",
    "world::parse_colour",
];

/// The store decides nothing: it names the core's types (the rows it maps) and calls only the
/// codecs of columns stored as text.
const STORE_MAY_CALL: &[&str] = &[
    "credentials::scopes_from_text",
    "credentials::scopes_to_text",
    "dataset::Direction::parse",
    "dataset::StepLength::new",
];

#[test]
fn the_cli_calls_no_core_logic() {
    let found = core_calls_in("src/cli", "crate::core::", CLI_MAY_CALL);
    assert!(
        found.is_empty(),
        "the command line calls into the core (move the work into an app use case):\n{}",
        found.join("\n")
    );
}

#[test]
fn the_store_calls_no_core_logic() {
    let found = core_calls_in("crates/enact-store/src", "enact_core::", STORE_MAY_CALL);
    assert!(
        found.is_empty(),
        "the store calls into the core (decisions belong to app):\n{}",
        found.join("\n")
    );
}

#[test]
fn core_calls_are_found_in_every_form() {
    let code = code_only(
        "use crate::core::verifier::{score_strict_predictions, StrictItem};\n\
         use crate::core::agreement;\n\
         fn f() { crate::core::world::simulate(&o); let x = crate::core::agreement::DEFAULT_SEED; }",
    );
    let offending: Vec<String> = core_paths(&code, "crate::core::")
        .into_iter()
        .filter(|p| !names_a_type_or_constant(p))
        .collect();
    assert_eq!(
        offending,
        [
            "crate::core::verifier::score_strict_predictions",
            "crate::core::agreement",
            "crate::core::world::simulate",
        ]
    );
}

/// SQL that changes rows or the schema, or announces a change: what makes a store function a
/// write.
const WRITE_WORDS: &[&str] = &[
    "INSERT INTO",
    "INSERT OR ",
    "DELETE FROM",
    "REPLACE INTO",
    " SET ",
    "CREATE TABLE",
    "CREATE TEMP",
    "DROP TABLE",
    "ALTER TABLE",
    "pg_notify",
];

/// Each function in `text` (its name, signature and body), found by `fn` and brace matching.
fn functions(text: &str) -> Vec<(String, &str, &str)> {
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(at) = text[from..].find("fn ").map(|i| from + i) {
        from = at + 3;
        let before = text[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let name: String = text[from..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let (Some(open), semicolon) = (text[from..].find('{'), text[from..].find(';')) else {
            break;
        };
        if semicolon.is_some_and(|s| s < open) {
            continue;
        }
        let body_start = from + open;
        let mut depth = 0usize;
        let mut end = text.len();
        for (i, c) in text[body_start..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = body_start + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        found.push((name, &text[at..body_start], &text[body_start..end]));
        from = end;
    }
    found
}

/// Store functions whose SQL writes but which take a plain connection: each such function
/// must take `&mut WriteConn`, which only a transaction holding a turn of the write gate is,
/// so that no caller can write outside the gate.
fn writes_outside_the_gate(text: &str) -> Vec<String> {
    functions(text)
        .into_iter()
        .filter(|(_, signature, body)| {
            signature.contains("&mut Conn") && WRITE_WORDS.iter().any(|w| body.contains(w))
        })
        .map(|(name, _, _)| name)
        .collect()
}

#[test]
fn every_store_function_that_writes_takes_a_gated_transaction() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/enact-store/src");
    let mut files = Vec::new();
    source_files(&dir, &mut files);
    let mut found = Vec::new();
    for file in files {
        // The connection layer, the gate and the migrations write outside any one function's
        // transaction by design.
        let name = file.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if matches!(name, "db.rs" | "gate.rs" | "migrations.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&file).expect("readable source");
        for function in writes_outside_the_gate(&text) {
            found.push(format!("{}: {function}", file.display()));
        }
    }
    assert!(
        found.is_empty(),
        "store functions write through a plain connection (take `&mut WriteConn`):\n{}",
        found.join("\n")
    );
}

#[test]
fn a_write_through_a_plain_connection_is_found() {
    let text = r#"
        pub async fn list(conn: &mut Conn) -> Result<Vec<i64>, sqlx::Error> {
            on!(conn, |c| sqlx::query_scalar("SELECT id FROM items").fetch_all(c).await)
        }
        pub async fn forget(conn: &mut Conn, id: i64) -> Result<(), sqlx::Error> {
            if id < 0 { return Ok(()); }
            on!(conn, |c| sqlx::query("DELETE FROM items WHERE id = $1").bind(id).execute(c).await)
        }
        pub async fn rename(conn: &mut WriteConn, id: i64) -> Result<(), sqlx::Error> {
            on!(conn, |c| sqlx::query("UPDATE items SET name = 'x'").execute(c).await)
        }
        pub async fn touch(conn: &mut Conn) -> Result<(), sqlx::Error> {
            on!(conn, |c| sqlx::query("UPDATE items SET seen = 1").execute(c).await)
        }
    "#;
    assert_eq!(writes_outside_the_gate(text), ["forget", "touch"]);
}
