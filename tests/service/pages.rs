//! The HTML site: home page, dataset browsing, item view, error pages.

use reqwest::StatusCode;

use crate::helpers::*;

#[tokio::test]
async fn empty_home_page_says_how_to_import() {
    let server = spawn_app_with(|_, _| async {}).await;
    let r = server.get("/").await;
    assert_eq!(r.status(), StatusCode::OK);
    let html = r.text().await.expect("body");
    assert!(html.contains("enact-hub import DATA_DIR"), "{html}");
    server.stop().await;
}

#[tokio::test]
async fn home_lists_datasets_with_counts_and_links() {
    let (server, _) = spawn_app_with_release().await;
    let html = server.get("/").await.text().await.expect("body");
    assert!(html.contains("href=\"/datasets/mini\""));
    assert!(
        html.contains("href=\"/datasets/mini?direction=inverse&#38;step_length=4\""),
        "{html}"
    );
    assert!(html.contains("4 items from 1 task ·"));
    server.stop().await;
}

#[tokio::test]
async fn browse_page_filters_items() {
    let (server, records) = spawn_app_with_release().await;
    let html = server
        .get("/datasets/mini?direction=forward")
        .await
        .text()
        .await
        .expect("body");
    assert!(html.contains(records[0]["id"].as_str().expect("id")));
    assert!(
        !html.contains(records[1]["id"].as_str().expect("id")),
        "inverse item shown"
    );
    assert!(html.contains("Items 1–2 of 2"));
    let r = server.get("/datasets/mini?step_length=zero").await;
    assert_eq!(r.status(), StatusCode::BAD_REQUEST);
    assert!(
        r.text()
            .await
            .expect("body")
            .contains("step_length: &#34;zero&#34; is not a whole number from 3 to 10")
    );
    server.stop().await;
}

#[tokio::test]
async fn item_page_shows_images_in_order_actions_and_question() {
    let (server, records) = spawn_app_with_release().await;
    let id = records[2]["id"].as_str().expect("id"); // forward, L = 4
    let html = server
        .get(&format!("/datasets/mini/items/{id}"))
        .await
        .text()
        .await
        .expect("body");
    let positions: Vec<usize> = [
        "alt=\"Image at position 1 of the item (Current State)\"",
        "alt=\"Image at position 2 of the item (Next State 1)\"",
        "alt=\"Image at position 3 of the item (Next State 2)\"",
        "alt=\"Image at position 4 of the item (Next State 3)\"",
    ]
    .iter()
    .map(|needle| {
        html.find(needle)
            .unwrap_or_else(|| panic!("{needle} missing"))
    })
    .collect();
    assert!(
        positions.windows(2).all(|w| w[0] < w[1]),
        "images out of order"
    );
    assert!(html.contains("[Action 3]"));
    assert!(html.contains("Now please provide your answer"));
    let (_, item) = server
        .get_json(&format!("/api/v1/datasets/mini/items/{id}"))
        .await;
    for img in item["images"].as_array().expect("images") {
        let src = img["url"].as_str().expect("url");
        assert!(html.contains(src), "page lacks {src}");
        assert_eq!(server.get(src).await.status(), StatusCode::OK);
    }
    let missing = server.get("/datasets/mini/items/nope").await;
    assert_eq!(missing.status(), StatusCode::NOT_FOUND);
    assert!(
        missing
            .text()
            .await
            .expect("body")
            .contains("no item &#39;nope&#39; in dataset &#39;mini&#39;")
    );
    server.stop().await;
}

#[tokio::test]
async fn every_demo_item_page_shows_its_images() {
    let server = spawn_app_with(|pool, _| async move {
        enact_hub::app::demo::load(&pool.clone().into())
            .await
            .expect("demo loads");
    })
    .await;
    let (_, list) = server
        .get_json("/api/v1/datasets/demo/items?per_page=500")
        .await;
    let items = list["items"].as_array().expect("items");
    let mut kinds = std::collections::BTreeSet::new();
    for item in items {
        kinds.insert((
            item["direction"].as_str().expect("dir").to_owned(),
            item["step_length"].as_u64().expect("L"),
        ));
        let id = item["id"].as_str().expect("id");
        let html = server
            .get(&format!("/datasets/demo/items/{id}"))
            .await
            .text()
            .await
            .expect("page");
        let (_, json) = server
            .get_json(&format!("/api/v1/datasets/demo/items/{id}"))
            .await;
        let images = json["images"].as_array().expect("images");
        assert_eq!(
            images.len() as u64,
            item["step_length"].as_u64().expect("L")
        );
        for img in images {
            let src = img["url"].as_str().expect("url");
            assert!(
                html.contains(&format!("src=\"{src}\"")),
                "{id}: page lacks {src}"
            );
            let r = server.get(src).await;
            assert_eq!(r.status(), StatusCode::OK);
            let png = r.bytes().await.expect("png");
            let decoded = image::load_from_memory(&png).expect("a PNG");
            assert_eq!((decoded.width(), decoded.height()), (512, 512));
        }
    }
    // Both directions at every step length 3..10.
    assert_eq!(kinds.len(), 16, "{kinds:?}");
    server.stop().await;
}

#[tokio::test]
async fn every_response_carries_the_security_headers() {
    let (server, _) = spawn_app_with_release().await;
    for path in [
        "/",
        "/datasets/mini",
        "/leaderboard/mini",
        "/leaderboard/mini/errors",
        "/login",
        "/api/docs",
        "/api/v1/datasets",
        "/favicon.ico",
        "/no/such/page",
    ] {
        let r = server.get(path).await;
        let h = r.headers();
        let csp = h["content-security-policy"].to_str().unwrap();
        assert!(
            csp.contains("script-src 'self'") && !csp.contains("unsafe-inline"),
            "{path}"
        );
        assert!(csp.contains("frame-ancestors 'none'"), "{path}");
        assert_eq!(h["x-content-type-options"], "nosniff", "{path}");
        assert_eq!(h["x-frame-options"], "DENY", "{path}");
        assert_eq!(h["referrer-policy"], "no-referrer", "{path}");
    }
    let icon = server.get("/favicon.ico").await;
    assert_eq!(icon.status(), StatusCode::OK);
    assert_eq!(icon.headers()["content-type"], "image/svg+xml");
    server.stop().await;
}
