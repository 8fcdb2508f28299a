//! The episode pages over HTTP: the upload form, the live description and its flags, drafts,
//! saving, two curators' comparison with planted differences, the resolution per key frame
//! and the export button's archive.

use std::io::Read;

use enact_hub::app::{Hub, episodes};
use enact_hub::core::audit::Actor;
use reqwest::StatusCode;
use serde_json::{Value, json};

use crate::annotate::{Browser, annotator, logged_in_on};
use crate::helpers::*;

/// A PNG of one colour.
fn png(shade: u8) -> Vec<u8> {
    let image = image::RgbImage::from_pixel(32, 24, image::Rgb([shade, 40, 200 - shade]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, image::ImageFormat::Png)
        .expect("encode");
    bytes.into_inner()
}

/// Episode `name` of `frames` frames, imported as the command line does.
async fn episode(server: &TestServer, name: &str, frames: u8) {
    let dir = server.dir().join(format!("frames-{name}"));
    std::fs::create_dir_all(&dir).expect("dir");
    for i in 0..frames {
        std::fs::write(dir.join(format!("{:05}.png", i + 1)), png(i * 10)).expect("frame");
    }
    episodes::import(
        &Hub::from(server.pool.clone()),
        &Actor::Operator("test".into()),
        &dir,
        name,
        "kitchen",
    )
    .await
    .expect("import");
}

fn node(name: &str, category: &str, states: &[&str]) -> Value {
    json!({"name": name, "category": category, "states": states})
}

/// Four key frames: the fridge opens, the robot grasps the apple with `hand`, the apple goes
/// into the fridge.
fn graphs(hand: &str) -> Value {
    let objects = |fridge: &[&str]| {
        vec![
            node("robot_r1", "robot", &[]),
            node("apple_1", "apple", &[]),
            node("fridge_1", "fridge", fridge),
        ]
    };
    json!({"key_frames": [
        {"frame": 0, "nodes": objects(&[]), "edges": []},
        {"frame": 1, "nodes": objects(&["Open"]), "edges": []},
        {"frame": 2, "nodes": objects(&["Open"]),
         "edges": [{"from": "robot_r1", "to": "apple_1", "states": [hand]}]},
        {"frame": 3, "nodes": objects(&["Open"]),
         "edges": [{"from": "apple_1", "to": "fridge_1", "states": ["Inside"]}]},
    ]})
}

async fn body(r: reqwest::Response) -> (StatusCode, String) {
    (r.status(), r.text().await.expect("body"))
}

#[tokio::test]
async fn curators_describe_draft_and_save_and_an_admin_compares_resolves_and_exports() {
    let server = spawn_app_with(|_, _| async {}).await;
    episode(&server, "kitchen", 5).await;
    for (name, admin) in [("alice", false), ("bob", false), ("root", true)] {
        annotator(&server, name, admin).await;
    }
    let (mut alice, alice_csrf) = logged_in_on(&server, "alice", "/annotate").await;

    // The page lists the frames and starts with no graph.
    let (status, html) = alice.text("/episodes/kitchen").await;
    assert_eq!(status, StatusCode::OK, "{html}");
    assert_eq!(html.matches("class=\"strip-frame\"").count(), 5);
    assert!(
        html.contains("data-graphs=\"{&#34;key_frames&#34;:[]}\""),
        "{html}"
    );

    // Described live: a copied key frame (no change) and an edge to a missing object are
    // flagged, by key frame and field, and nothing is stored.
    let mut flawed = graphs("LeftGrasping");
    flawed["key_frames"][1] = flawed["key_frames"][0].clone();
    flawed["key_frames"][1]["frame"] = json!(1);
    flawed["key_frames"][3]["edges"][0]["to"] = json!("oven_1");
    let r = alice
        .post_json("/episodes/kitchen/describe", Some(&alice_csrf), &flawed)
        .await;
    let described: Value = r.json().await.expect("JSON");
    let problems = described["problems"].to_string();
    assert!(problems.contains("nothing changed"), "{problems}");
    assert!(problems.contains("edges[0].to"), "{problems}");
    assert_eq!(described["transitions"][0]["components"], json!([]));
    let r = alice
        .post_json(
            "/episodes/kitchen/describe",
            Some(&alice_csrf),
            &graphs("LeftGrasping"),
        )
        .await;
    let described: Value = r.json().await.expect("JSON");
    assert_eq!(described["problems"], json!([]));
    assert_eq!(
        described["transitions"][0]["sentences"],
        json!(["The fridge now becomes open."])
    );
    assert_eq!(
        described["transitions"][0]["components"],
        json!(["node_add_the fridge_Open"])
    );

    // A draft survives a reload; saving it as it is is refused with the key frame named, and
    // the draft stays.
    let r = alice
        .post_json("/episodes/kitchen/draft", Some(&alice_csrf), &flawed)
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let (_, html) = alice.text("/episodes/kitchen").await;
    assert!(html.contains("resumed from your draft"), "{html}");
    assert!(html.contains("oven_1"), "{html}");
    let (status, refusal) = body(
        alice
            .post_json("/episodes/kitchen/graphs", Some(&alice_csrf), &flawed)
            .await,
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{refusal}");
    assert!(refusal.contains("key frame 3 (frame 3)"), "{refusal}");
    let (_, html) = alice.text("/episodes/kitchen").await;
    assert!(html.contains("resumed from your draft"), "{html}");

    // Saved for real by two curators, with one planted difference: the hand.
    let r = alice
        .post_json(
            "/episodes/kitchen/graphs",
            Some(&alice_csrf),
            &graphs("LeftGrasping"),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);
    let (_, html) = alice.text("/episodes/kitchen").await;
    assert!(
        !html.contains("resumed from your draft"),
        "the draft outlived the save"
    );
    let (mut bob, bob_csrf) = logged_in_on(&server, "bob", "/annotate").await;
    let r = bob
        .post_json(
            "/episodes/kitchen/graphs",
            Some(&bob_csrf),
            &graphs("RightGrasping"),
        )
        .await;
    assert_eq!(r.status(), StatusCode::OK);

    // The comparison: transitions 1 -> 2 and 2 -> 3 each differ by one component on each
    // side; 0 -> 1 and the apple's move are shared: 2 shared, 2 only alice's, 2 only bob's.
    let (mut root, root_csrf) = logged_in_on(&server, "root", "/admin").await;
    let (status, html) = root
        .text("/admin/episodes/kitchen/compare?a=alice&b=bob")
        .await;
    assert_eq!(status, StatusCode::OK, "{html}");
    assert!(
        html.contains("<dt>Components both drew</dt><dd>2</dd>"),
        "{html}"
    );
    assert!(html.contains("<dt>Only alice</dt><dd>2</dd>"), "{html}");
    assert!(html.contains("<dt>Only bob</dt><dd>2</dd>"), "{html}");
    assert!(html.contains("<dd>33.3 %</dd>"), "{html}");
    assert!(
        html.contains("edge_add_the robot r1_the apple_RightGrasping"),
        "{html}"
    );

    // Resolved per key frame: alice's first two, bob's last two; exported with bob's hand.
    let r = root
        .post_form(
            "/admin/episodes/kitchen/resolve",
            &[
                ("csrf", &root_csrf),
                ("a", "alice"),
                ("b", "bob"),
                ("frame_0", "alice"),
                ("frame_1", "alice"),
                ("frame_2", "bob"),
                ("frame_3", "bob"),
                ("frame_4", ""),
            ],
        )
        .await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    let back = r.headers()["location"]
        .to_str()
        .expect("location")
        .to_owned();
    let (_, html) = root.text(&back).await;
    assert!(
        html.contains("Resolved: 4 key frames from 2 curator(s)."),
        "{html}"
    );
    let r = root.get("/admin/episodes/kitchen/export").await;
    assert_eq!(r.status(), StatusCode::OK);
    assert_eq!(r.headers()["content-type"], "application/x-tar");
    let tar = r.bytes().await.expect("archive");
    let mut archive = tar::Archive::new(tar.as_ref());
    let mut names = Vec::new();
    let mut graph_file = String::new();
    for entry in archive.entries().expect("entries") {
        let mut entry = entry.expect("entry");
        let path = entry.path().expect("path").to_string_lossy().into_owned();
        if path == "replayed_activities/kitchen/scene_graph_0.json" {
            entry.read_to_string(&mut graph_file).expect("read");
        }
        names.push(path);
    }
    assert!(
        names.contains(&"replayed_activities/kitchen/external_sensor1/00004.png".to_owned()),
        "{names:?}"
    );
    assert!(graph_file.contains("RightGrasping"), "{graph_file}");
    assert!(!graph_file.contains("LeftGrasping"), "{graph_file}");

    // Choosing a key frame a curator never marked is refused by name.
    let r = root
        .post_form(
            "/admin/episodes/kitchen/resolve",
            &[("csrf", &root_csrf), ("frame_4", "alice")],
        )
        .await;
    let (status, text) = body(r).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{text}");
    assert!(text.contains("alice") && text.contains("frame 4"), "{text}");
    server.stop().await;
}

/// A multipart body of `fields` then `files` (name, bytes) under "frames".
fn multipart(fields: &[(&str, &str)], files: &[(&str, Vec<u8>)]) -> (String, Vec<u8>) {
    let boundary = "episode-upload-boundary";
    let mut out = Vec::new();
    for (name, value) in fields {
        out.extend(
            format!(
                "--{boundary}\r\nContent-Disposition: form-data; name=\"{name}\"\r\n\r\n{value}\r\n"
            )
            .as_bytes(),
        );
    }
    for (file, bytes) in files {
        out.extend(
            format!(
                "--{boundary}\r\nContent-Disposition: form-data; name=\"frames\"; \
                 filename=\"{file}\"\r\nContent-Type: image/png\r\n\r\n"
            )
            .as_bytes(),
        );
        out.extend(bytes);
        out.extend(b"\r\n");
    }
    out.extend(format!("--{boundary}--\r\n").as_bytes());
    (format!("multipart/form-data; boundary={boundary}"), out)
}

async fn upload(
    browser: &Browser,
    server: &TestServer,
    content_type: &str,
    bytes: Vec<u8>,
) -> reqwest::Response {
    reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .expect("client")
        .post(server.url("/admin/episodes"))
        .header("cookie", browser.cookie_header())
        .header("content-type", content_type)
        .body(bytes)
        .send()
        .await
        .expect("upload")
}

#[tokio::test]
async fn the_upload_form_stores_frames_in_name_order_and_refuses_what_is_not_a_frame() {
    let server = spawn_app_with(|_, _| async {}).await;
    annotator(&server, "root", true).await;
    let (root, csrf) = logged_in_on(&server, "root", "/admin").await;
    let fields = [
        ("csrf", csrf.as_str()),
        ("name", "desk"),
        ("scene", "workspace"),
    ];

    // Sent out of order, with a path as some browsers send it: stored by name.
    let (kind, bytes) = multipart(
        &fields,
        &[
            ("frame10.png", png(100)),
            ("dir/frame2.png", png(20)),
            ("frame1.png", png(10)),
        ],
    );
    let r = upload(&root, &server, &kind, bytes).await;
    assert_eq!(r.status(), StatusCode::SEE_OTHER);
    assert_eq!(r.headers()["location"], "/episodes/desk");
    let stored = episodes::get(&Hub::from(server.pool.clone()), "desk")
        .await
        .expect("stored");
    let names: Vec<&str> = stored.frames.iter().map(|f| f.file_name.as_str()).collect();
    assert_eq!(names, ["frame1.png", "frame2.png", "frame10.png"]);
    assert_eq!(stored.summary.scene, "workspace");

    // A text file among the frames: refused by name, nothing stored.
    let fields = [("csrf", csrf.as_str()), ("name", "desk2")];
    let (kind, bytes) = multipart(
        &fields,
        &[
            ("00001.png", png(1)),
            ("notes.txt", b"not a frame".to_vec()),
        ],
    );
    let (status, text) = body(upload(&root, &server, &kind, bytes).await).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{text}");
    assert!(text.contains("notes.txt"), "{text}");
    assert!(
        episodes::get(&Hub::from(server.pool.clone()), "desk2")
            .await
            .is_err()
    );

    // The token must come first: frames before it are refused unread.
    let (kind, bytes) = multipart(&[], &[("00001.png", png(1))]);
    let r = upload(&root, &server, &kind, bytes).await;
    assert_eq!(r.status(), StatusCode::FORBIDDEN);
    server.stop().await;
}
