//! The pages' languages: the catalogue check (every key a template, the page script or the
//! web layer uses is in every locale, and no locale holds a key nothing uses), the locale a
//! request gets (saved preference, `Accept-Language`, English), the switch, translated error
//! pages and English API errors, and what is never translated.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use enact_hub::app::refusal::{Detail, Refusal};
use enact_hub::web::i18n::{Locale, SCRIPT_MESSAGES, Tr, catalogue_keys};
use regex::Regex;
use reqwest::StatusCode;

use crate::annotate::{Browser, PASSWORD, annotator, assign, logged_in_on};
use crate::helpers::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` (recursively) whose name ends with one of `extensions`.
fn files(dir: &Path, extensions: &[&str]) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut pending = vec![dir.to_owned()];
    while let Some(dir) = pending.pop() {
        for entry in std::fs::read_dir(&dir).expect("read dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                pending.push(path);
            } else if extensions
                .iter()
                .any(|e| path.to_string_lossy().ends_with(e))
            {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// The message keys used, with where each is used: lookups in the templates
/// (`tr.t("key")`, `tr.t_n("key", ...)`, ...), lookups and `msg("key")` in the web layer's
/// Rust, and `m("key")` in the page scripts (which must also be in `SCRIPT_MESSAGES`, the
/// list the page hands its script).
fn used_keys() -> Vec<(String, String)> {
    let lookup = Regex::new(r#"(?:\btr\.t\w*|\bmsg)\(\s*"([a-z0-9-]+)""#).expect("regex");
    let script = Regex::new(r#"\bm\("([a-z0-9-]+)""#).expect("regex");
    let mut used = Vec::new();
    let sources = files(&root().join("templates"), &[".html", ".svg"])
        .into_iter()
        .chain(files(&root().join("crates/enact-web/src"), &[".rs"]));
    for path in sources {
        let text = std::fs::read_to_string(&path).expect("read source");
        for c in lookup.captures_iter(&text) {
            used.push((c[1].to_owned(), path.display().to_string()));
        }
    }
    for path in files(&root().join("static"), &[".js"]) {
        let text = std::fs::read_to_string(&path).expect("read script");
        for c in script.captures_iter(&text) {
            assert!(
                SCRIPT_MESSAGES.iter().any(|(k, _)| *k == &c[1]),
                "{}: the script uses message '{}', which SCRIPT_MESSAGES (crates/enact-web/src/i18n.rs) \
                 does not hand it",
                path.display(),
                &c[1]
            );
            used.push((c[1].to_owned(), path.display().to_string()));
        }
    }
    used
}

#[test]
fn every_used_key_is_in_every_locale_and_every_key_is_used() {
    let used = used_keys();
    assert!(
        used.len() > 100,
        "the scan found only {} lookups",
        used.len()
    );
    let used_set: BTreeSet<&str> = used.iter().map(|(k, _)| k.as_str()).collect();
    let mut problems = Vec::new();
    for locale in Locale::ALL {
        let keys = catalogue_keys(locale.catalogue_source())
            .unwrap_or_else(|e| panic!("locales/{}/pages.ftl does not parse: {e}", locale.tag()));
        let mut seen = BTreeSet::new();
        for k in &keys {
            if !seen.insert(k.as_str()) {
                problems.push(format!("locales/{}: key '{k}' twice", locale.tag()));
            }
        }
        for (key, place) in &used {
            if !seen.contains(key.as_str()) {
                problems.push(format!(
                    "locales/{}/pages.ftl lacks '{key}' (used in {place})",
                    locale.tag()
                ));
            }
        }
        for key in &seen {
            if !used_set.contains(key) {
                problems.push(format!(
                    "locales/{}/pages.ftl: '{key}' is used by no template, script or handler",
                    locale.tag()
                ));
            }
        }
    }
    problems.dedup();
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every typed refusal has its message in every locale, and says it with each of its details;
/// no message a page can show names a command-line flag (a reader of a page cannot give one).
#[test]
fn every_refusal_is_worded_in_every_locale_and_no_message_names_a_flag() {
    let flag = Regex::new(r"(^|[\s(`'“])--[a-z]").expect("regex");
    let mut problems = Vec::new();
    for locale in Locale::ALL {
        let tr = Tr::new(locale);
        for refusal in Refusal::examples() {
            let text = tr.refusal(&refusal);
            if text.starts_with("refusal-") {
                problems.push(format!(
                    "{}: no message for {}",
                    locale.tag(),
                    refusal.code()
                ));
            }
            for (name, detail) in refusal.details() {
                let shown = match detail {
                    Detail::Text(t) => t,
                    Detail::Number(n) => enact_hub::web::i18n::decimal(n as f64, 0),
                    Detail::Time(t) => tr.date_time(&t),
                };
                // What a message chooses its words by (a plural's count, the action, how a
                // part was revealed, whether a reveal is scheduled) is its grammar, not always
                // shown.
                let selector = ["count", "action", "how", "scheduled", "listed"].contains(&name);
                if !selector && !text.contains(&shown) {
                    problems.push(format!(
                        "{}: {} does not show its {name} ({shown}): {text}",
                        locale.tag(),
                        refusal.code()
                    ));
                }
            }
        }
        for line in locale.catalogue_source().lines() {
            if !line.trim_start().starts_with('#') && flag.is_match(line) {
                problems.push(format!("locales/{}: names a flag: {line}", locale.tag()));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The scan sees a flag where one is.
    assert!(flag.is_match("use --skip-invalid to import"));
    assert!(!flag.is_match("2026-11-29 -- a note"));
}

#[test]
fn the_check_sees_a_missing_key() {
    // The scan must find lookups in each kind of source, or the check above proves nothing.
    let used = used_keys();
    for (key, file) in [
        ("queue-title", "queue.html"),
        ("direction-forward", "annotate.rs"),
        ("js-placed", "annotate.js"),
        ("error-reason-404", "error.rs"),
    ] {
        assert!(
            used.iter().any(|(k, p)| k == key && p.ends_with(file)),
            "the scan misses '{key}' in {file}"
        );
    }
}

pub(crate) async fn page(
    server: &TestServer,
    path: &str,
    accept_language: &str,
) -> (StatusCode, String) {
    let r = reqwest::Client::new()
        .get(server.url(path))
        .header("accept-language", accept_language)
        .send()
        .await
        .expect("get");
    (r.status(), r.text().await.expect("body"))
}

#[tokio::test]
async fn accept_language_chooses_the_pages_language() {
    let (server, _) = spawn_app_with_release().await;
    let (status, zh) = page(&server, "/", "fr;q=1, zh-CN;q=0.8, en;q=0.5").await;
    assert_eq!(status, StatusCode::OK);
    assert!(zh.contains(r#"<html lang="zh-CN" dir="ltr">"#), "{zh}");
    assert!(zh.contains("数据集"));
    assert!(
        zh.contains(r#"value="en" lang="en""#),
        "the switch offers English: {zh}"
    );
    let (_, en) = page(&server, "/", "de, en-GB;q=0.9, zh;q=0.3").await;
    assert!(en.contains(r#"<html lang="en" dir="ltr">"#), "{en}");
    let (_, none) = page(&server, "/", "de").await;
    assert!(none.contains(r#"<html lang="en" dir="ltr">"#));
    server.stop().await;
}

#[tokio::test]
async fn error_pages_are_translated_and_api_errors_stay_english_with_a_code() {
    let (server, _) = spawn_app_with_release().await;
    let (status, html) = page(&server, "/datasets/nope", "zh-CN").await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(html.contains(r#"<html lang="zh-CN" dir="ltr">"#), "{html}");
    assert!(html.contains("404 未找到"), "{html}");
    // A typed refusal is said in the page's language.
    assert!(html.contains("没有名为“nope”的数据集"), "{html}");
    assert!(!html.contains(r#"<span lang="en">"#), "{html}");
    let (status, html) = page(&server, "/studies/nope", "zh-CN").await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(html.contains("没有名为“nope”的研究"), "{html}");
    // A refusal still worded by its use case is shown as it is, marked as English.
    let (status, html) = page(&server, "/datasets/mini/compare?a=Human&b=1", "zh-CN").await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert!(
        html.contains(r#"<span lang="en">`a`: the Human row pools"#),
        "{html}"
    );
    let r = reqwest::Client::new()
        .get(server.url("/api/v1/datasets/nope/items"))
        .header("accept-language", "zh-CN")
        .send()
        .await
        .expect("get");
    assert_eq!(r.status(), StatusCode::NOT_FOUND);
    let body: serde_json::Value = r.json().await.expect("json");
    let error = body["error"].as_str().expect("error");
    assert!(error.is_ascii() && error.contains("nope"), "{error}");
    assert_eq!(body["code"], "no_dataset");
    assert_eq!(body["details"], serde_json::json!({"dataset": "nope"}));
    server.stop().await;
}

/// The layout check's pseudo-locale: a page right to left with every message in ⟦…⟧ when the
/// cookie names it by hand, and nothing a user can pick by accident (not the switch, not
/// `Accept-Language`).
#[tokio::test]
async fn only_a_hand_set_cookie_chooses_the_right_to_left_pseudo_locale() {
    let (server, _) = spawn_app_with_release().await;
    let reply = server
        .call(reqwest::Method::GET, "/")
        .header("cookie", "enact_lang=ar-XB")
        .send()
        .await;
    assert_eq!(reply.status, StatusCode::OK);
    let html = reply.text;
    assert!(html.contains(r#"<html lang="ar-XB" dir="rtl">"#), "{html}");
    assert!(html.contains("⟦Datasets"), "{html}");
    // The switch offers the real locales only.
    assert!(!html.contains(r#"value="ar-XB""#), "{html}");
    assert!(html.contains(r#"value="en""#) && html.contains(r#"value="zh-CN""#));
    let (_, asked) = page(&server, "/", "ar-XB, ar").await;
    assert!(asked.contains(r#"<html lang="en" dir="ltr">"#), "{asked}");
    let mut visitor = Browser::new(&server);
    let r = visitor.post_form("/locale", &[("locale", "ar-XB")]).await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    server.stop().await;
}

#[tokio::test]
async fn the_switch_sets_a_cookie_and_saves_a_signed_in_annotators_choice() {
    let (server, records) = spawn_app_with_release().await;
    let alice = annotator(&server, "alice", false).await;
    let first = records[0]["id"].as_str().expect("id").to_owned();
    assign(&server, alice, &[first.as_str()]).await;

    // Anyone: a cookie, then back to the page the switch was on.
    let mut visitor = Browser::new(&server);
    let r = visitor
        .post_form(
            "/locale",
            &[("locale", "zh-CN"), ("back", "/leaderboard/x")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert_eq!(r.headers()["location"], "/leaderboard/x");
    assert!(visitor.cookie_header().contains("enact_lang=zh-CN"));
    let (_, home) = visitor.text("/").await;
    assert!(home.contains(r#"<html lang="zh-CN" dir="ltr">"#));
    // Never somewhere else.
    let r = visitor
        .post_form("/locale", &[("locale", "en"), ("back", "//evil.example/")])
        .await;
    assert_eq!(r.headers()["location"], "/");
    let r = visitor.post_form("/locale", &[("locale", "xx")]).await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("locale: &#34;xx&#34; is not one of: en, zh-CN")
    );

    // A signed-in annotator: the choice is saved and follows her to another browser.
    let (mut first_browser, _) = logged_in_on(&server, "alice", "/annotate").await;
    first_browser
        .post_form("/locale", &[("locale", "zh-CN"), ("back", "/annotate")])
        .await;
    let mut second = Browser::new(&server);
    let r = second.login("alice", PASSWORD).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert!(second.cookie_header().contains("enact_lang=zh-CN"));
    let (status, queue) = second.text("/annotate").await;
    assert_eq!(status, StatusCode::OK);
    assert!(queue.contains("我的队列"), "{queue}");
    assert!(queue.contains("待完成"), "statuses are translated: {queue}");

    // The item page: chrome in Chinese, the benchmark's text as the dataset holds it.
    let (status, item) = second.text(&format!("/annotate/mini/{first}")).await;
    assert_eq!(status, StatusCode::OK, "{item}");
    assert!(item.contains("提交答案"), "{item}");
    assert!(
        item.contains("不做翻译"),
        "the page says what stays untranslated"
    );
    let question = records[0]["question"].as_str().expect("question");
    for line in question.lines().filter(|l| !l.is_empty()) {
        assert!(
            item.contains(&askama_escape(line)),
            "the question is shown untranslated: {line}"
        );
    }
    assert!(
        item.contains("data-messages="),
        "the script's messages are on the page"
    );
    assert!(item.contains("已放入槽位"), "{item}");
    server.stop().await;
}

/// `text` as the templates escape it into HTML.
fn askama_escape(text: &str) -> String {
    text.replace('&', "&#38;")
        .replace('<', "&#60;")
        .replace('>', "&#62;")
        .replace('"', "&#34;")
        .replace('\'', "&#39;")
}
