//! The admin page for API tokens: create (shown once), use, revoke, and who may do it.

use reqwest::StatusCode;

use crate::annotate::{Browser, PASSWORD, annotator, hidden_csrf, logged_in_on};
use crate::helpers::*;

async fn logged_in(server: &TestServer, name: &str) -> (Browser, String) {
    logged_in_on(server, name, "/admin/tokens").await
}

/// The secret between the `new-token` code tags of the result page.
fn shown_token(html: &str) -> String {
    let start = html.find("<code id=\"new-token\">").expect("a new token") + 21;
    let end = start + html[start..].find("</code>").expect("end of token");
    html[start..end].to_owned()
}

async fn submit(server: &TestServer, token: &str, body: String) -> StatusCode {
    submit_to(server, "mini", "model=m", token, body)
        .await
        .status
}

#[tokio::test]
async fn admins_create_tokens_that_work_and_revoke_them_at_once() {
    let (server, records) = spawn_app_with_release().await;
    annotator(&server, "root", true).await;
    let (mut admin, csrf) = logged_in(&server, "root").await;
    let (_, html) = admin.text("/admin").await;
    assert!(
        html.contains("href=\"/admin/tokens\""),
        "linked from /admin"
    );

    let r = admin
        .post_form(
            "/admin/tokens",
            &[
                ("csrf", &csrf),
                ("name", "team-a"),
                ("role", "submitter"),
                ("daily_quota", ""),
                ("total_quota", "5"),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    assert_eq!(r.headers()["cache-control"], "no-store");
    let html = r.text().await.expect("body");
    let token = shown_token(&html);
    assert!(token.starts_with("ehub_"), "{token}");
    assert!(html.contains("team-a") && html.contains("submit,read_own"));

    // The secret is shown once: the listing never carries it again.
    let (status, listing) = admin.text("/admin/tokens").await;
    assert_eq!(status, StatusCode::OK);
    assert!(!listing.contains(&token));
    assert!(listing.contains("never"), "not used yet");

    assert_eq!(
        submit(&server, &token, ground_truth_answers(&records)).await,
        StatusCode::CREATED
    );
    let (_, listing) = admin.text("/admin/tokens").await;
    assert!(!listing.contains("never"), "last use is shown: {listing}");

    let id: i64 = count(
        &server.pool,
        "SELECT id FROM api_tokens WHERE account = (SELECT id FROM accounts WHERE name = 'team-a')",
    )
    .await;
    let r = admin
        .post_form(
            "/admin/tokens/revoke",
            &[("csrf", &csrf), ("token", &id.to_string())],
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    assert!(r.text().await.expect("body").contains("revoked"));
    assert_eq!(
        submit(&server, &token, ground_truth_answers(&records)).await,
        StatusCode::UNAUTHORIZED
    );
    // Revoking twice says so.
    let r = admin
        .post_form(
            "/admin/tokens/revoke",
            &[("csrf", &csrf), ("token", &id.to_string())],
        )
        .await;
    assert_eq!(r.status(), StatusCode::NOT_FOUND);

    // Bad input is named.
    let r = admin
        .post_form(
            "/admin/tokens",
            &[("csrf", &csrf), ("name", "team-b"), ("daily_quota", "lots")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("daily quota: &#34;lots&#34; is not a whole number of 0 or more")
    );
    // A negative number is refused by the use case, as on the API.
    let r = admin
        .post_form(
            "/admin/tokens",
            &[("csrf", &csrf), ("name", "team-c"), ("total_quota", "-3")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("total_quota: &#34;-3&#34; is not a whole number of 0 or more")
    );
    server.stop().await;
}

#[tokio::test]
async fn only_admins_with_the_page_csrf_token_manage_tokens() {
    let (server, _) = spawn_app_with_release().await;
    annotator(&server, "root", true).await;
    annotator(&server, "alice", false).await;
    let tokens = || async { count(&server.pool, "SELECT count(*) FROM api_tokens").await };

    // Not logged in: redirected to the login form, and posts are refused.
    let mut anonymous = Browser::new(&server);
    let r = anonymous.get("/admin/tokens").await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    let r = anonymous
        .post_form("/admin/tokens", &[("name", "mallory")])
        .await;
    assert_eq!(r.status(), StatusCode::UNAUTHORIZED);

    // An annotator gets 403 on the page, and on a post even with a valid CSRF token.
    let mut alice = Browser::new(&server);
    alice.login("alice", PASSWORD).await;
    let (status, _) = alice.text("/admin/tokens").await;
    assert_eq!(status, StatusCode::FORBIDDEN);
    let (_, queue) = alice.text("/annotate").await;
    let alice_csrf = hidden_csrf(&queue);
    let r = alice
        .post_form(
            "/admin/tokens",
            &[("csrf", &alice_csrf), ("name", "mallory")],
        )
        .await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);

    // An admin without the CSRF token, or with a wrong one, is refused too.
    let (mut admin, _) = logged_in(&server, "root").await;
    for fields in [
        vec![("name", "mallory")],
        vec![("name", "mallory"), ("csrf", "f00d")],
    ] {
        let r = admin.post_form("/admin/tokens", &fields).await;
        assert_eq!(r.status(), StatusCode::FORBIDDEN, "{fields:?}");
        let r = admin
            .post_form("/admin/tokens/revoke", &[("token", "1")])
            .await;
        assert_eq!(r.status(), StatusCode::FORBIDDEN);
    }
    assert_eq!(tokens().await, 0, "no token was created");
    server.stop().await;
}
