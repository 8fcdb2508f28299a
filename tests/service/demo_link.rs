//! `serve --demo`'s login link: one click logs the demo admin in, whose queue already holds both
//! directions at every step length of the demo; a link works once.

use enact_hub::app::Hub;
use reqwest::StatusCode;

use crate::annotate::Browser;
use crate::helpers::*;

#[tokio::test]
async fn the_demo_link_logs_in_once_to_a_balanced_queue() {
    let server = spawn_app_with(|pool, _| async move {
        enact_hub::app::demo::load(&Hub::from(pool)).await.unwrap();
    })
    .await;
    let hub = Hub::from(server.pool.clone());
    let link = enact_hub::app::demo::annotator_link(&hub).await.unwrap();

    let mut browser = Browser::new(&server);
    let r = browser.get(&format!("/login/link/{link}")).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert_eq!(r.headers()["location"], "/annotate");
    let queue = browser.get("/annotate").await;
    assert_eq!(queue.status(), StatusCode::OK);

    let kinds: Vec<(String, i64)> = db!(
        server.pool,
        fetch_all,
        sqlx::query_as(
            "SELECT DISTINCT i.direction, i.step_length FROM assignments g \
             JOIN items i ON i.id = g.item JOIN annotators n ON n.id = g.annotator \
             WHERE n.name = 'demo-admin'",
        )
    )
    .unwrap();
    let all: Vec<(String, i64)> = db!(
        server.pool,
        fetch_all,
        sqlx::query_as("SELECT DISTINCT direction, step_length FROM items")
    )
    .unwrap();
    assert!(kinds.len() >= 4, "{kinds:?}");
    assert_eq!(
        kinds.len(),
        all.len(),
        "every direction × length of the demo is queued"
    );

    // Used up: the same link again is refused, and a second link adds no second sample.
    let mut again = Browser::new(&server);
    assert_eq!(
        again.get(&format!("/login/link/{link}")).await.status(),
        StatusCode::NOT_FOUND
    );
    // The refusal is a typed one: in the page's language, naming no command a visitor can't run.
    let (status, zh) = crate::i18n::page(&server, &format!("/login/link/{link}"), "zh-CN").await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    assert!(zh.contains("此登录链接无效或已被使用"), "{zh}");
    assert!(!zh.contains("serve --demo"), "{zh}");
    let assigned = || async { count(&server.pool, "SELECT count(*) FROM assignments").await };
    let before = assigned().await;
    let second = enact_hub::app::demo::annotator_link(&hub).await.unwrap();
    assert_ne!(second, link);
    assert_eq!(assigned().await, before);
    assert_eq!(
        again.get(&format!("/login/link/{second}")).await.status(),
        StatusCode::SEE_OTHER
    );
    server.stop().await;
}
